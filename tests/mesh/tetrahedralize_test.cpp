#include "hof/mesh/tetrahedralize.h"

#include <gtest/gtest.h>

#include "hof/mesh/boundary.h"
#include "hof/mesh/mesh_report.h"
#include "hof/mesh/surface_check.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mesh {
namespace {

// Closed outward surface of the box [o, o+s], 12 triangles.
TriMesh box_surface(const Vec3& o = Vec3::Zero(), double s = 1.0) {
  TriMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.push_back(o + s * Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  }
  // Quads (outward), split into two triangles each.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

TEST(Tetrahedralize, BoxSurfaceCheckedBeforeMeshing) { ASSERT_TRUE(check_surface(box_surface()).closed_outward()); }

TEST(Tetrahedralize, BoxFillsItsVolumeWithPositiveTets) {
  auto mesh = tetrahedralize(box_surface(), {});
  ASSERT_TRUE(mesh.has_value()) << mesh.error().to_string();
  double volume = 0.0;
  for (const Tet& t : mesh->tets) {
    const auto c = tet_corners(mesh->nodes, t);
    const double v = tet_signed_volume(c[0], c[1], c[2], c[3]);
    EXPECT_GT(v, 0.0);
    volume += v;
  }
  EXPECT_NEAR(volume, 1.0, 1e-12);
  EXPECT_TRUE(check_surface(mesh->nodes, mesh->triangles).closed_outward());
}

TEST(Tetrahedralize, VolumeBoundIsRespected) {
  TetrahedralizeOptions options;
  options.max_volume_m3 = 1e-3;
  auto mesh = tetrahedralize(box_surface(), options);
  ASSERT_TRUE(mesh.has_value()) << mesh.error().to_string();
  EXPECT_GE(mesh->tets.size(), 1000u);
  for (const Tet& t : mesh->tets) {
    const auto c = tet_corners(mesh->nodes, t);
    EXPECT_LE(tet_signed_volume(c[0], c[1], c[2], c[3]), 1e-3 * (1 + 1e-9));
  }
  EXPECT_EQ(make_mesh_report(*mesh).problems.size(), 0u);
}

TEST(Tetrahedralize, OpenSurfaceIsAClearError) {
  TriMesh open = box_surface();
  open.triangles.pop_back();
  auto mesh = tetrahedralize(open, {}, "lid.obj");
  ASSERT_FALSE(mesh.has_value());
  EXPECT_EQ(mesh.error().code, ErrorCode::kMeshing);
  EXPECT_NE(mesh.error().message.find("lid.obj: the surface is not closed"), std::string::npos) << mesh.error().message;
}

TEST(Tetrahedralize, SelfIntersectingSurfaceIsAClearError) {
  // Two overlapping closed boxes in one surface: every edge is manifold, but faces cross.
  TriMesh a = box_surface();
  const TriMesh b = box_surface(Vec3(0.5, 0.5, 0.5));
  for (Tri t : b.triangles) {
    for (NodeIndex& v : t) v += 8;
    a.triangles.push_back(t);
  }
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  ASSERT_TRUE(check_surface(a).closed_manifold());
  auto mesh = tetrahedralize(a, {}, "boxes.obj");
  ASSERT_FALSE(mesh.has_value());
  EXPECT_EQ(mesh.error().code, ErrorCode::kMeshing);
  EXPECT_NE(mesh.error().message.find("intersects itself"), std::string::npos) << mesh.error().message;
}

TEST(Tetrahedralize, RejectsOptionsTetGenCannotHonour) {
  TetrahedralizeOptions options;
  options.radius_edge_ratio = 0.5;  // TetGen would not terminate
  auto mesh = tetrahedralize(box_surface(), options);
  ASSERT_FALSE(mesh.has_value());
  EXPECT_EQ(mesh.error().code, ErrorCode::kInvalidArgument);
  options = {};
  options.max_volume_m3 = -1.0;
  EXPECT_FALSE(tetrahedralize(box_surface(), options).has_value());
}

TEST(Tetrahedralize, NonFiniteVertexIsRejected) {
  TriMesh m = box_surface();
  m.vertices[3].x() = std::numeric_limits<double>::quiet_NaN();
  auto mesh = tetrahedralize(m, {}, "nan.obj");
  ASSERT_FALSE(mesh.has_value());
  EXPECT_NE(mesh.error().message.find("vertex 3"), std::string::npos);
}

}  // namespace
}  // namespace hof::mesh
