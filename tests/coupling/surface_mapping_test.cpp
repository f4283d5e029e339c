// How a surface follows the simulated volume (src/hof/coupling/surface_mapping.cpp), for each
// kind of mapping: by index (the surface's vertices are volume nodes), barycentric in
// tetrahedra, onto triangles, and trilinear on a hexahedral grid (an affine field reproduced
// exactly, and a sparse-grid liver's fine surface following its grid; moved from
// tests/mechanics/hexahedron_fem_test.cpp so that the mechanics tests link the mechanics module
// only). Forces go back by the transpose: the same virtual work on both sides.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <random>

#include "hof/coupling/surface_mapping.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/surface_check.h"
#include "mechanics/test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_grid;
using testing::distort_interior;
using testing::hex_field;

// ---- trilinear mapping ----------------------------------------------------------------------

TEST(TrilinearMapping, ReproducesAnAffineDeformationExactly) {
  mesh::HexGrid grid = box_grid({4, 3, 3}, Vec3(0.3, 0.2, 0.2));
  distort_interior(grid, 0.2);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 200; ++i) points.emplace_back(0.3 * u(random), 0.2 * u(random), 0.2 * u(random));
  points.emplace_back(0.31, 0.1, 0.1);  // just outside: extrapolated from the nearest cell
  auto mapping = coupling::SurfaceMapping::trilinear(grid.nodes, grid.hexes, points);
  ASSERT_TRUE(mapping) << mapping.error().to_string();
  Mat3 a;
  a << 1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.2;
  const Vec3 shift(0.3, -0.1, 0.2);
  std::vector<double> x;
  for (const Vec3& p : grid.nodes) {
    const Vec3 q = a * p + shift;
    x.insert(x.end(), {q.x(), q.y(), q.z()});
  }
  std::vector<Vec3> mapped(points.size());
  mapping->apply(x, mapped);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_LT((mapped[i] - (a * points[i] + shift)).norm(), 1e-12) << "point " << i;
    std::array<std::int32_t, 8> nodes{};
    std::array<double, 8> weights{};
    const std::array<std::int32_t, 1> vertex{static_cast<std::int32_t>(i)};
    const std::array<double, 1> one{1.0};
    ASSERT_EQ(mapping->point_weights(vertex, one, nodes, weights), 8u);
    EXPECT_NEAR(weights[0] + weights[1] + weights[2] + weights[3] + weights[4] + weights[5] + weights[6] + weights[7],
                1.0, 1e-12);
    if (i < 200) {
      for (double w : weights) EXPECT_GE(w, -1e-9) << "point " << i << " is inside: no extrapolation";
    }
  }
  // A triangle's point carries up to 24 (node, weight) pairs.
  std::array<std::int32_t, coupling::SurfaceMapping::kMaxPointWeights> nodes{};
  std::array<double, coupling::SurfaceMapping::kMaxPointWeights> weights{};
  const std::array<std::int32_t, 3> triangle{0, 1, 2};
  const std::array<double, 3> bary{0.2, 0.3, 0.5};
  EXPECT_EQ(mapping->point_weights(triangle, bary, nodes, weights), 24u);
}

// ---- the sparse-grid liver --------------------------------------------------------------------

TEST(SparseGridLiver, RunsStablyAndItsFineSurfaceFollows) {
  auto read = mesh::read_mesh(HOF_SOURCE_DIR "/data/models/liver-medium.obj");
  ASSERT_TRUE(read) << read.error().to_string();
  const mesh::TriMesh surface{read->mesh.nodes, read->mesh.triangles};
  auto grid = mesh::sparse_grid(surface, {10, 10, 10});
  ASSERT_TRUE(grid) << grid.error().to_string();

  ModelConfig c;
  c.name = "liver";
  c.positions = grid->nodes;
  c.hexahedra = grid->hexes;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1060.0;
  c.gravity_m_per_s2 = Vec3(0, 0, -9.81);
  c.force_fields.push_back(hex_field(FemMethod::kLarge, 30000.0, 0.45));
  // Held by the nodes of its top layer of cells (it hangs from them and sags).
  const Vec3 h = grid->cell_size();
  FixedConstraintConfig held;
  held.box = std::pair<Vec3, Vec3>(Vec3(-1.0, -1.0, grid->max.z() - 2.5 * h.z()), Vec3(1.0, 1.0, 1.0));
  c.fixed.push_back(held);
  c.ode.kind = OdeSolverKind::kEulerImplicit;
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.linear.kind = LinearSolverKind::kConjugateGradient;
  c.linear.iterations = 25;
  c.linear.tolerance = c.linear.threshold = 1e-9;
  c.dt_s = 0.02;
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  EXPECT_NEAR(
      model->total_mass_kg(),
      1060.0 *
          [&] {
            double v = 0.0;
            for (const mesh::Hex& hex : grid->hexes) v += mesh::hex_volume(grid->nodes, hex);
            return v;
          }(),
      1e-9);

  auto mapping = coupling::SurfaceMapping::trilinear(grid->nodes, grid->hexes, surface.vertices);
  ASSERT_TRUE(mapping) << mapping.error().to_string();
  MechanicalState state = make_state(*model);
  std::vector<Vec3> mapped(surface.vertices.size());
  mapping->apply({state.x.data(), static_cast<std::size_t>(state.x.size())}, mapped);
  for (std::size_t v = 0; v < mapped.size(); ++v) {
    EXPECT_LT((mapped[v] - surface.vertices[v]).norm(), 1e-12);
    // Every surface vertex lies in a cell the surface crosses: interpolated, not extrapolated.
    std::array<std::int32_t, 8> nodes{};
    std::array<double, 8> weights{};
    const std::array<std::int32_t, 1> vertex{static_cast<std::int32_t>(v)};
    const std::array<double, 1> one{1.0};
    ASSERT_EQ(mapping->point_weights(vertex, one, nodes, weights), 8u);
    for (double w : weights) EXPECT_GE(w, -1e-9) << "vertex " << v;
  }

  double largest = 0.0;
  for (int s = 0; s < 100; ++s) {
    ASSERT_TRUE(step(*model, state)) << "step " << s << ": " << state.divergence.component << ": "
                                     << state.divergence.reason;
    ASSERT_TRUE(state.x.allFinite());
    for (std::size_t n = 0; n < grid->nodes.size(); ++n) {
      largest = std::max(largest, (state.position(static_cast<std::int32_t>(n)) - grid->nodes[n]).norm());
    }
  }
  std::printf("sparse-grid liver: %zu nodes, %zu hexahedra, largest displacement %.2f mm\n", grid->nodes.size(),
              grid->hexes.size(), 1e3 * largest);
  EXPECT_GT(largest, 1e-3);  // it sags under its weight
  EXPECT_LT(largest, 0.05);  // and stays bounded (the liver is 0.22 m long)

  // The fine surface follows: each mapped vertex is its cell's combination of the moved
  // nodes, the surface keeps its volume (ν = 0.45: nearly incompressible) and no triangle
  // turns over.
  mapping->apply({state.x.data(), static_cast<std::size_t>(state.x.size())}, mapped);
  double moved = 0.0;
  for (std::size_t v = 0; v < mapped.size(); ++v) {
    ASSERT_TRUE(mapped[v].allFinite());
    moved = std::max(moved, (mapped[v] - surface.vertices[v]).norm());
  }
  EXPECT_GT(moved, 0.5 * largest);
  const double rest_volume = mesh::check_surface(surface).signed_volume_m3;
  const double volume = mesh::check_surface(mapped, surface.triangles).signed_volume_m3;
  EXPECT_NEAR(volume, rest_volume, 0.03 * rest_volume);
  for (const mesh::Tri& t : surface.triangles) {
    const Vec3 before =
        (surface.vertices[t[1]] - surface.vertices[t[0]]).cross(surface.vertices[t[2]] - surface.vertices[t[0]]);
    const Vec3 after = (mapped[t[1]] - mapped[t[0]]).cross(mapped[t[2]] - mapped[t[0]]);
    EXPECT_GT(before.normalized().dot(after.normalized()), 0.5);
  }
}

}  // namespace
}  // namespace hof::mechanics

namespace hof::coupling {
namespace {

std::vector<double> flat(const std::vector<Vec3>& points) {
  std::vector<double> x;
  for (const Vec3& p : points) x.insert(x.end(), {p.x(), p.y(), p.z()});
  return x;
}

// An affine map x → A x + b of every volume node, flattened.
std::vector<double> affine_field(const std::vector<Vec3>& nodes, const Mat3& a, const Vec3& b) {
  std::vector<Vec3> moved;
  for (const Vec3& p : nodes) moved.push_back(a * p + b);
  return flat(moved);
}

Mat3 some_deformation() {
  Mat3 a;
  a << 1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.2;
  return a;
}

// The force F at surface vertex v does the same work on a volume motion u as on the surface's
// motion under the map: F · (M u)_v = (Mᵀ F) · u.
void expect_transpose(const SurfaceMapping& mapping, std::size_t volume_nodes, std::int32_t v) {
  std::mt19937 random(9);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> u(3 * volume_nodes);
  for (double& x : u) x = uniform(random);
  std::vector<Vec3> mapped(mapping.surface_vertex_count());
  mapping.apply(u, mapped);
  const Vec3 force(0.3, -1.2, 0.7);
  std::vector<double> forces(3 * volume_nodes, 0.0);
  mapping.add_vertex_force(v, force, forces);
  double work = 0.0, total_x = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) work += forces[i] * u[i];
  for (std::size_t i = 0; i < volume_nodes; ++i) total_x += forces[3 * i];
  EXPECT_NEAR(work, force.dot(mapped[static_cast<std::size_t>(v)]), 1e-12);
  EXPECT_NEAR(total_x, force.x(), 1e-12);  // the weights sum to one: nothing lost
}

TEST(SurfaceMappingByIndex, SurfaceVerticesAreVolumeNodes) {
  const std::vector<Vec3> nodes{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const std::vector<Vec3> surface{nodes[3], nodes[1]};
  const std::vector<mesh::NodeIndex> to_volume{3, 1};
  auto mapping = SurfaceMapping::by_index(nodes, surface, to_volume);
  ASSERT_TRUE(mapping) << mapping.error().to_string();
  EXPECT_TRUE(mapping->is_identity());
  EXPECT_EQ(mapping->surface_vertex_count(), 2u);
  EXPECT_EQ(mapping->dominant_node(0), 3);
  std::vector<Vec3> mapped(2);
  mapping->apply(affine_field(nodes, some_deformation(), Vec3(1, 2, 3)), mapped);
  EXPECT_LT((mapped[0] - (some_deformation() * nodes[3] + Vec3(1, 2, 3))).norm(), 1e-15);
  std::vector<double> forces(12, 0.0);
  mapping->add_vertex_force(1, Vec3(4, 5, 6), forces);
  EXPECT_EQ(forces, (std::vector<double>{0, 0, 0, 4, 5, 6, 0, 0, 0, 0, 0, 0}));
}

TEST(SurfaceMappingByIndex, AVertexAwayFromItsNodeOrAnIndexOutOfRangeIsRefused) {
  const std::vector<Vec3> nodes{Vec3(0, 0, 0), Vec3(1, 0, 0)};
  const std::vector<Vec3> surface{Vec3(0, 0, 0), Vec3(1, 0, 1e-6)};
  const std::vector<mesh::NodeIndex> to_volume{0, 1};
  const auto far = SurfaceMapping::by_index(nodes, surface, to_volume);
  ASSERT_FALSE(far);
  EXPECT_EQ(far.error().code, ErrorCode::kInvalidMesh);
  EXPECT_NE(far.error().to_string().find("surface vertex 1 is 1e-06 m from volume node 1"), std::string::npos)
      << far.error().to_string();
  EXPECT_TRUE(SurfaceMapping::by_index(nodes, surface, to_volume, 1e-5));  // within a looser tolerance
  const std::vector<mesh::NodeIndex> past{0, 2};
  const auto out = SurfaceMapping::by_index(nodes, surface, past);
  ASSERT_FALSE(out);
  EXPECT_NE(out.error().to_string().find("vertex 1 maps to node 2 of 2"), std::string::npos);
  const std::vector<mesh::NodeIndex> one{0};
  EXPECT_FALSE(SurfaceMapping::by_index(nodes, surface, one));
}

TEST(SurfaceMappingBarycentric, FollowsAnAffineMotionExactlyInsideAndOutside) {
  const mechanics::testing::BoxMesh box = mechanics::testing::box_mesh(3, 2, 2, Vec3(0.3, 0.2, 0.2));
  std::mt19937 random(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 100; ++i) points.emplace_back(0.3 * u(random), 0.2 * u(random), 0.2 * u(random));
  points.emplace_back(0.32, 0.1, 0.1);  // just outside: extrapolated from the nearest tetrahedron
  points.emplace_back(0.0, 0.0, 0.0);   // on a corner node
  auto mapping = SurfaceMapping::barycentric(box.nodes, box.tets, points);
  ASSERT_TRUE(mapping) << mapping.error().to_string();
  EXPECT_FALSE(mapping->is_identity());
  const Vec3 shift(0.3, -0.1, 0.2);
  std::vector<Vec3> mapped(points.size());
  mapping->apply(affine_field(box.nodes, some_deformation(), shift), mapped);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_LT((mapped[i] - (some_deformation() * points[i] + shift)).norm(), 1e-12) << "point " << i;
  }
  EXPECT_EQ(mapping->dominant_node(static_cast<std::int32_t>(points.size() - 1)), 0);
  expect_transpose(*mapping, box.nodes.size(), 7);
  expect_transpose(*mapping, box.nodes.size(), 100);
}

TEST(SurfaceMappingBarycentric, NoTetrahedraIsAnError) {
  const std::vector<Vec3> nodes{Vec3::Zero()};
  const auto mapping = SurfaceMapping::barycentric(nodes, std::span<const mesh::Tet>{}, nodes);
  ASSERT_FALSE(mapping);
  EXPECT_NE(mapping.error().to_string().find("the volume has no tetrahedra"), std::string::npos);
}

TEST(SurfaceMappingOntoTriangles, FollowsTheClosestPointOfTheTriangles) {
  // A unit square membrane in z = 0; surface vertices on it and 0.05 above it.
  const std::vector<Vec3> nodes{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  const std::vector<mesh::Tri> triangles{{0, 1, 2}, {0, 2, 3}};
  const std::vector<Vec3> points{Vec3(0.7, 0.2, 0.0), Vec3(0.25, 0.5, 0.05), Vec3(1.5, 0.5, 0.0)};
  auto mapping = SurfaceMapping::onto_triangles(nodes, triangles, points);
  ASSERT_TRUE(mapping) << mapping.error().to_string();
  // An in-plane affine motion is followed exactly by the points on the plane.
  Mat3 a = Mat3::Identity();
  a(0, 1) = 0.3;
  a(1, 1) = 1.2;
  std::vector<Vec3> mapped(points.size());
  mapping->apply(affine_field(nodes, a, Vec3(0, 0, 0.1)), mapped);
  EXPECT_LT((mapped[0] - (a * points[0] + Vec3(0, 0, 0.1))).norm(), 1e-12);
  // A point above the membrane follows its projection (SOFA drops the normal offset).
  EXPECT_LT((mapped[1] - (a * Vec3(0.25, 0.5, 0) + Vec3(0, 0, 0.1))).norm(), 1e-12);
  // A point beyond the edge x = 1 follows the edge's closest point.
  EXPECT_LT((mapped[2] - (a * Vec3(1, 0.5, 0) + Vec3(0, 0, 0.1))).norm(), 1e-12);
  expect_transpose(*mapping, nodes.size(), 0);
  expect_transpose(*mapping, nodes.size(), 1);
}

TEST(SurfaceMappingOntoTriangles, NoTrianglesOrANodeOutOfRangeIsAnError) {
  const std::vector<Vec3> nodes{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const auto none = SurfaceMapping::onto_triangles(nodes, std::span<const mesh::Tri>{}, nodes);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().to_string().find("neither tetrahedra nor triangles"), std::string::npos);
  const std::vector<mesh::Tri> bad{{0, 1, 3}};
  const auto out = SurfaceMapping::onto_triangles(nodes, bad, nodes);
  ASSERT_FALSE(out);
  EXPECT_NE(out.error().to_string().find("triangle 0 uses node 3 of 3"), std::string::npos) << out.error().to_string();
}

TEST(SurfaceMappingTrilinear, ForcesGoBackByTheTransposeAndNoHexahedraIsAnError) {
  auto grid = mesh::regular_grid({3, 2, 2}, Vec3::Zero(), Vec3(0.2, 0.1, 0.1));
  ASSERT_TRUE(grid);
  const std::vector<Vec3> points{Vec3(0.05, 0.03, 0.07), Vec3(0.17, 0.09, 0.01)};
  auto mapping = SurfaceMapping::trilinear(grid->nodes, grid->hexes, points);
  ASSERT_TRUE(mapping) << mapping.error().to_string();
  expect_transpose(*mapping, grid->nodes.size(), 0);
  expect_transpose(*mapping, grid->nodes.size(), 1);
  const auto none = SurfaceMapping::trilinear(grid->nodes, std::span<const mesh::Hex>{}, points);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().to_string().find("the volume has no hexahedra"), std::string::npos);
}

}  // namespace
}  // namespace hof::coupling
