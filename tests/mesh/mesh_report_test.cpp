// What `hof mesh info` reports (src/hof/mesh/mesh_report.cpp): sizes, volume and quality of a
// regular tetrahedron and a cube of six, and each problem it must name — inverted and
// degenerate tetrahedra, unused nodes, an open or inward-facing surface, an empty mesh.

#include "hof/mesh/mesh_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "hof/mesh/boundary.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mesh {
namespace {

bool has_problem(const MeshReport& r, const std::string& text) {
  return std::find(r.problems.begin(), r.problems.end(), text) != r.problems.end();
}

// Positively oriented whatever the corners' order.
Tet oriented(const std::vector<Vec3>& nodes, Tet t) {
  const auto c = tet_corners(nodes, t);
  if (tet_signed_volume(c[0], c[1], c[2], c[3]) < 0) std::swap(t[2], t[3]);
  return t;
}

// The regular tetrahedron of edge 2√2: volume a³/(6√2) = 8/3, every dihedral arccos(1/3).
Mesh regular_tet() {
  Mesh m;
  m.nodes = {Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)};
  m.tets = {oriented(m.nodes, {0, 1, 2, 3})};
  return m;
}

// The unit cube as six tetrahedra around its diagonal 0–7 (corner bits: 1 = +x, 2 = +y, 4 = +z).
Mesh unit_cube() {
  Mesh m;
  for (int c = 0; c < 8; ++c) m.nodes.emplace_back(c & 1, (c >> 1) & 1, (c >> 2) & 1);
  for (const auto& [a, b] : {std::pair{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}})
    m.tets.push_back(oriented(m.nodes, {0, a, b, 7}));
  return m;
}

TEST(MeshReport, ARegularTetrahedronIsPerfect) {
  const MeshReport r = make_mesh_report(regular_tet());
  EXPECT_EQ(r.nodes, 4);
  EXPECT_EQ(r.tets, 1);
  EXPECT_EQ(r.edges, 6);
  EXPECT_EQ(r.surface_triangles, 4);
  EXPECT_EQ(r.surface_vertices, 4);
  EXPECT_NEAR(r.volume_m3, 8.0 / 3.0, 1e-14);
  const double dihedral = std::acos(1.0 / 3.0) * 180.0 / std::numbers::pi;  // 70.53°
  EXPECT_NEAR(r.quality.min_dihedral_deg, dihedral, 1e-9);
  EXPECT_NEAR(r.quality.max_dihedral_deg, dihedral, 1e-9);
  EXPECT_NEAR(r.quality.min_radius_ratio, 1.0, 1e-12);
  EXPECT_EQ(r.bbox_min, Vec3(-1, -1, -1));
  EXPECT_EQ(r.bbox_max, Vec3(1, 1, 1));
  EXPECT_TRUE(r.problems.empty()) << r.problems.front();
}

TEST(MeshReport, ACubeOfSixTetrahedraHasTheCubesVolumeEdgesAndSurface) {
  const MeshReport r = make_mesh_report(unit_cube());
  EXPECT_EQ(r.nodes, 8);
  EXPECT_EQ(r.tets, 6);
  EXPECT_EQ(r.edges, 19);  // 12 sides, 6 face diagonals, the main diagonal
  EXPECT_EQ(r.surface_triangles, 12);
  EXPECT_EQ(r.surface_vertices, 8);
  EXPECT_NEAR(r.volume_m3, 1.0, 1e-14);
  EXPECT_NEAR(r.quality.min_volume_m3, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(r.quality.max_volume_m3, 1.0 / 6.0, 1e-15);
  EXPECT_LT(r.quality.min_radius_ratio, 1.0);
  EXPECT_NEAR(r.quality.min_dihedral_deg, 45.0, 1e-9);  // Kuhn tets: 45°, 60° and 90°
  EXPECT_NEAR(r.quality.max_dihedral_deg, 90.0, 1e-9);
  EXPECT_TRUE(r.problems.empty()) << r.problems.front();
}

TEST(MeshReport, InvertedAndDegenerateTetrahedraAreCountedFoundAndNamed) {
  Mesh m = unit_cube();
  std::swap(m.tets[2][0], m.tets[2][1]);
  m.nodes.push_back(Vec3(2, 0, 0));
  m.nodes.push_back(Vec3(2, 1, 0));
  m.nodes.push_back(Vec3(2, 0, 1));
  m.nodes.push_back(Vec3(2, 1, 1));  // four coplanar nodes
  m.tets.push_back({8, 9, 10, 11});
  const MeshReport r = make_mesh_report(m);
  EXPECT_EQ(r.quality.inverted, 1);
  EXPECT_EQ(r.quality.degenerate, 1);
  EXPECT_TRUE(has_problem(r, "1 inverted tetrahedra (negative volume)"));
  EXPECT_TRUE(has_problem(r, "1 degenerate tetrahedra (zero volume)"));
  EXPECT_EQ(find_inverted_tets(m.nodes, m.tets), (std::vector<std::int32_t>{2, 6}));
}

TEST(MeshReport, NodesUsedByNoElementAreNamed) {
  Mesh m = regular_tet();
  m.nodes.push_back(Vec3(5, 0, 0));
  const MeshReport r = make_mesh_report(m);
  EXPECT_EQ(r.unused_nodes, 1);
  EXPECT_TRUE(has_problem(r, "1 nodes used by no element"));
  EXPECT_EQ(r.bbox_max.x(), 5.0);  // the box is of every node
}

TEST(MeshReport, ASurfaceAloneEnclosesItsVolumeAndItsDefectsAreNamed) {
  const Mesh solid = regular_tet();
  const BoundarySurface boundary = extract_boundary(solid.nodes, solid.tets);
  Mesh surface;
  surface.nodes = boundary.surface.vertices;
  surface.triangles = boundary.surface.triangles;
  MeshReport r = make_mesh_report(surface);
  EXPECT_EQ(r.tets, 0);
  EXPECT_EQ(r.file_triangles, 4);
  EXPECT_EQ(r.edges, 6);
  EXPECT_NEAR(r.volume_m3, 8.0 / 3.0, 1e-14);
  EXPECT_TRUE(r.problems.empty()) << r.problems.front();
  // Turned inside out.
  Mesh inward = surface;
  for (Tri& t : inward.triangles) std::swap(t[1], t[2]);
  EXPECT_TRUE(has_problem(make_mesh_report(inward), "surface normals point inward (negative enclosed volume)"));
  // A face missing: three edges have one triangle.
  Mesh open = surface;
  open.triangles.pop_back();
  EXPECT_TRUE(has_problem(make_mesh_report(open), "surface is open: 3 boundary edges"));
}

TEST(MeshReport, AnEmptyMeshSaysSo) {
  const MeshReport r = make_mesh_report(Mesh{});
  EXPECT_TRUE(has_problem(r, "no tetrahedra and no triangles"));
  EXPECT_EQ(r.nodes, 0);
}

}  // namespace
}  // namespace hof::mesh
