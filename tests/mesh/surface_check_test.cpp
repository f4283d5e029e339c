#include "hof/mesh/surface_check.h"

#include <gtest/gtest.h>

namespace hof::mesh {
namespace {

// Closed outward tetrahedron surface on vertices base..base+3.
std::vector<Tri> tet_surface(NodeIndex base) {
  return {{base + 1, base + 2, base + 3},
          {base, base + 3, base + 2},
          {base, base + 1, base + 3},
          {base, base + 2, base + 1}};
}

std::vector<Vec3> unit_tet(const Vec3& offset = Vec3::Zero()) {
  return {offset, offset + Vec3(1, 0, 0), offset + Vec3(0, 1, 0), offset + Vec3(0, 0, 1)};
}

TEST(SurfaceCheck, ClosedOutwardTetrahedron) {
  const SurfaceCheck c = check_surface(unit_tet(), tet_surface(0));
  EXPECT_TRUE(c.closed_outward());
  EXPECT_EQ(c.edges, 6);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.euler_characteristic, 2);
  EXPECT_NEAR(c.signed_volume_m3, 1.0 / 6.0, 1e-15);
}

TEST(SurfaceCheck, InwardSurfaceIsClosedButNotOutward) {
  auto tris = tet_surface(0);
  for (Tri& t : tris) std::swap(t[1], t[2]);
  const SurfaceCheck c = check_surface(unit_tet(), tris);
  EXPECT_TRUE(c.closed_manifold());
  EXPECT_FALSE(c.closed_outward());
  EXPECT_LT(c.signed_volume_m3, 0.0);
}

TEST(SurfaceCheck, MissingFaceMakesItOpen) {
  auto tris = tet_surface(0);
  tris.pop_back();
  const SurfaceCheck c = check_surface(unit_tet(), tris);
  EXPECT_FALSE(c.closed_manifold());
  EXPECT_EQ(c.boundary_edges, 3);
  ASSERT_TRUE(c.first_bad_edge.has_value());
}

TEST(SurfaceCheck, FlippedFaceIsMisoriented) {
  auto tris = tet_surface(0);
  std::swap(tris[0][1], tris[0][2]);
  const SurfaceCheck c = check_surface(unit_tet(), tris);
  EXPECT_EQ(c.misoriented_edges, 3);
  EXPECT_FALSE(c.closed_manifold());
}

TEST(SurfaceCheck, ThirdTriangleOnAnEdgeIsNonManifold) {
  auto verts = unit_tet();
  verts.push_back(Vec3(1, 1, -1));
  auto tris = tet_surface(0);
  tris.push_back({0, 1, 4});  // a fin on edge 0-1
  const SurfaceCheck c = check_surface(verts, tris);
  EXPECT_EQ(c.non_manifold_edges, 1);
  EXPECT_FALSE(c.closed_manifold());
}

TEST(SurfaceCheck, TwoTetsSharingOneVertexArePinched) {
  // Second tet reuses vertex 0 of the first: every edge is fine, the vertex is not.
  auto verts = unit_tet();
  for (const Vec3& p : unit_tet(Vec3(-1, -1, -1))) verts.push_back(p);
  auto tris = tet_surface(0);
  for (Tri t : tet_surface(4)) {
    for (NodeIndex& v : t) {
      if (v == 7) v = 0;  // glue the far corner (0,0,0) of the second tet to vertex 0
    }
    tris.push_back(t);
  }
  verts[7] = verts[0];
  const SurfaceCheck c = check_surface(verts, tris);
  EXPECT_EQ(c.boundary_edges, 0);
  EXPECT_EQ(c.non_manifold_edges, 0);
  EXPECT_EQ(c.non_manifold_vertices, 1);
  EXPECT_FALSE(c.closed_manifold());
}

TEST(SurfaceCheck, CountsComponentsAndDegenerateTriangles) {
  auto verts = unit_tet();
  for (const Vec3& p : unit_tet(Vec3(5, 0, 0))) verts.push_back(p);
  auto tris = tet_surface(0);
  for (const Tri& t : tet_surface(4)) tris.push_back(t);
  SurfaceCheck c = check_surface(verts, tris);
  EXPECT_EQ(c.components, 2);
  EXPECT_EQ(c.euler_characteristic, 4);
  EXPECT_TRUE(c.closed_outward());
  tris.push_back({0, 0, 1});
  c = check_surface(verts, tris);
  EXPECT_EQ(c.degenerate_triangles, 1);
  EXPECT_FALSE(c.closed_manifold());
}

}  // namespace

}  // namespace hof::mesh
