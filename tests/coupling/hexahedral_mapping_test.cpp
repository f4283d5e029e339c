// The trilinear surface mapping on a hexahedral grid (coupling::SurfaceMapping::trilinear): an
// affine field reproduced exactly, and a sparse-grid liver's fine surface following its grid.
// Moved from tests/mechanics/hexahedron_fem_test.cpp so that the mechanics tests link the
// mechanics module only.

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
    EXPECT_NEAR(weights[0] + weights[1] + weights[2] + weights[3] + weights[4] + weights[5] + weights[6] + weights[7], 1.0,
                1e-12);
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
  EXPECT_NEAR(model->total_mass_kg(), 1060.0 * [&] {
    double v = 0.0;
    for (const mesh::Hex& hex : grid->hexes) v += mesh::hex_volume(grid->nodes, hex);
    return v;
  }(), 1e-9);

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
  EXPECT_GT(largest, 1e-3);   // it sags under its weight
  EXPECT_LT(largest, 0.05);   // and stays bounded (the liver is 0.22 m long)

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
    const Vec3 before = (surface.vertices[t[1]] - surface.vertices[t[0]]).cross(surface.vertices[t[2]] - surface.vertices[t[0]]);
    const Vec3 after = (mapped[t[1]] - mapped[t[0]]).cross(mapped[t[2]] - mapped[t[0]]);
    EXPECT_GT(before.normalized().dot(after.normalized()), 0.5);
  }
}


}  // namespace
}  // namespace hof::mechanics
