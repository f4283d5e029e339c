#include "hof/mesh/boundary.h"

#include <gtest/gtest.h>

#include "hof/mesh/surface_check.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mesh {
namespace {

// A unit cube split into 6 positively oriented tetrahedra around the diagonal 0-6.
Mesh cube_mesh() {
  Mesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  m.tets = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  for (Tet& t : m.tets) {
    const auto c = tet_corners(m.nodes, t);
    if (tet_signed_volume(c[0], c[1], c[2], c[3]) < 0) std::swap(t[2], t[3]);
  }
  return m;
}

TEST(Boundary, SingleTetHasFourOutwardFaces) {
  const std::vector<Vec3> nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const BoundarySurface b = extract_boundary(nodes, {{0, 1, 2, 3}});
  ASSERT_EQ(b.surface.triangles.size(), 4u);
  const SurfaceCheck check = check_surface(b.surface);
  EXPECT_TRUE(check.closed_outward());
  EXPECT_NEAR(check.signed_volume_m3, 1.0 / 6.0, 1e-15);
  // Every face normal points away from the centroid.
  const Vec3 centroid(0.25, 0.25, 0.25);
  for (const Tri& t : b.surface.triangles) {
    const Vec3& p0 = b.surface.vertices[t[0]];
    const Vec3 n = (b.surface.vertices[t[1]] - p0).cross(b.surface.vertices[t[2]] - p0);
    EXPECT_GT(n.dot(p0 - centroid), 0.0);
  }
}

TEST(Boundary, InvertedTetFacesStillPointOutOfIt) {
  const std::vector<Vec3> nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const BoundarySurface b = extract_boundary(nodes, {{0, 2, 1, 3}});  // negative orientation
  EXPECT_TRUE(check_surface(b.surface).closed_outward());
}

TEST(Boundary, CubeInteriorFacesAreDroppedAndMapIsConsistent) {
  const Mesh m = cube_mesh();
  const BoundarySurface b = extract_boundary(m.nodes, m.tets);
  EXPECT_EQ(b.surface.triangles.size(), 12u);  // two per cube face
  EXPECT_EQ(b.surface.vertices.size(), 8u);
  const SurfaceCheck check = check_surface(b.surface);
  EXPECT_TRUE(check.closed_outward());
  EXPECT_NEAR(check.signed_volume_m3, 1.0, 1e-14);
  EXPECT_EQ(check.euler_characteristic, 2);
  for (std::size_t s = 0; s < b.surface_to_volume.size(); ++s) {
    const NodeIndex v = b.surface_to_volume[s];
    EXPECT_EQ(b.volume_to_surface[v], static_cast<std::int32_t>(s));
    EXPECT_EQ(b.surface.vertices[s], m.nodes[v]);
  }
  for (std::size_t f = 0; f < b.volume_triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(b.surface_to_volume[b.surface.triangles[f][k]], b.volume_triangles[f][k]);
    }
    // The owning tet contains the face's three nodes.
    const Tet& t = m.tets[b.triangle_tet[f]];
    for (NodeIndex n : b.volume_triangles[f]) EXPECT_NE(std::find(t.begin(), t.end(), n), t.end());
  }
}

TEST(Boundary, InteriorNodeIsNotOnSurface) {
  // Four tets around an interior apex at the centroid of an outer tet.
  const std::vector<Vec3> nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.25, 0.25, 0.25}};
  const std::vector<Tet> tets = {{4, 1, 2, 3}, {0, 4, 2, 3}, {0, 1, 4, 3}, {0, 1, 2, 4}};
  const BoundarySurface b = extract_boundary(nodes, tets);
  EXPECT_EQ(b.surface.triangles.size(), 4u);
  EXPECT_EQ(b.volume_to_surface[4], -1);
  EXPECT_TRUE(check_surface(b.surface).closed_outward());
}

TEST(Edges, CubeHasNineteenUniqueEdges) {
  // 12 cube edges + 6 face diagonals + 1 body diagonal.
  EXPECT_EQ(tet_edges(cube_mesh().tets).size(), 19u);
  EXPECT_EQ(tet_edges({{0, 1, 2, 3}}).size(), 6u);
  EXPECT_EQ(triangle_edges({{0, 1, 2}, {0, 2, 3}}).size(), 5u);
}

}  // namespace
}  // namespace hof::mesh
