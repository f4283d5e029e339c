// The standard liver under gravity: static equilibrium by the static solver and by implicit
// Euler agree; results do not depend on the number of threads; the SOFA liver loads and runs.

#include <gtest/gtest.h>

#include "hof/mechanics/step.h"
#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"

namespace hof::mechanics {
namespace {

// Three surface nodes near the top of the right lobe, spread out: the liver hangs from them.
std::vector<std::int32_t> three_top_nodes(const std::vector<Vec3>& nodes) {
  std::vector<std::int32_t> picked;
  for (const Vec3& target : {Vec3(0.06, 0.0, 1.0), Vec3(0.0, 0.04, 1.0), Vec3(-0.03, -0.03, 1.0)}) {
    std::int32_t best = 0;
    double best_score = 1e30;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      // Closest in the horizontal plane, highest first.
      const double score = (nodes[i] - target).head<2>().norm() - 0.5 * nodes[i].z();
      if (score < best_score) {
        best_score = score;
        best = static_cast<std::int32_t>(i);
      }
    }
    picked.push_back(best);
  }
  return picked;
}

ModelConfig liver_config(const mesh::Mesh& liver, OdeSolverKind solver) {
  ModelConfig c;
  c.name = "liver";
  c.positions = liver.nodes;
  c.tets = liver.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1060.0;  // liver tissue (literature.md §6)
  c.gravity_m_per_s2 = Vec3(0, 0, -9.81);  // z is up in the generated liver
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{30000.0, 0.45, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  FixedConstraintConfig fixed;
  fixed.indices = three_top_nodes(liver.nodes);
  c.fixed.push_back(fixed);
  c.ode.kind = solver;
  c.dt_s = 0.02;
  return c;
}

const mesh::Mesh& liver(mesh::LiverResolution r) {
  static std::map<mesh::LiverResolution, mesh::Mesh> cache;
  auto it = cache.find(r);
  if (it == cache.end()) it = cache.emplace(r, *mesh::generate_liver(r)).first;
  return it->second;
}

TEST(LiverEquilibrium, StaticSolverAndImplicitEulerAgree) {
  const mesh::Mesh& m = liver(mesh::LiverResolution::kSimple);

  ModelConfig s = liver_config(m, OdeSolverKind::kStatic);
  s.ode.newton_iterations = 100;
  s.ode.newton_residual_tolerance_n = 1e-7;
  s.linear.kind = LinearSolverKind::kSparseLdlt;
  auto static_model = build_model(s);
  ASSERT_TRUE(static_model) << static_model.error().to_string();
  MechanicalState static_state = make_state(*static_model);
  ASSERT_TRUE(step(*static_model, static_state)) << static_state.divergence.reason;
  EXPECT_LT(static_state.stats.residual_force_n, 1e-7);
  EXPECT_LT(max_residual_force(*static_model, static_state), 1e-7);

  ModelConfig d = liver_config(m, OdeSolverKind::kEulerImplicit);
  d.ode.rayleigh_mass = 0.1;
  d.ode.rayleigh_stiffness = 0.1;
  d.linear.iterations = 200;
  d.linear.tolerance = 1e-16;
  d.linear.threshold = 1e-30;
  auto dynamic_model = build_model(d);
  ASSERT_TRUE(dynamic_model) << dynamic_model.error().to_string();
  MechanicalState dynamic_state = make_state(*dynamic_model);
  int steps = 0;
  while (steps < 3000 && (steps < 10 || max_residual_force(*dynamic_model, dynamic_state) > 1e-6)) {
    ASSERT_TRUE(step(*dynamic_model, dynamic_state)) << dynamic_state.divergence.reason;
    ++steps;
  }
  EXPECT_LT(steps, 3000) << "implicit Euler did not settle";

  double max_displacement = 0.0, max_difference = 0.0;
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const auto n = static_cast<std::int32_t>(i);
    max_displacement = std::max(max_displacement, (static_state.position(n) - m.nodes[i]).norm());
    max_difference = std::max(max_difference, (static_state.position(n) - dynamic_state.position(n)).norm());
  }
  EXPECT_GT(max_displacement, 0.005);  // it really sags
  EXPECT_LT(max_difference, 1e-3 * max_displacement) << "after " << steps << " implicit steps";
}

MechanicalState run_with_threads(const mesh::Mesh& m, int threads, int steps, bool block_jacobi = true) {
  ModelConfig c = liver_config(m, OdeSolverKind::kEulerImplicit);
  c.threads = threads;
  c.ode.rayleigh_mass = 0.1;
  c.ode.rayleigh_stiffness = 0.1;
  c.linear.block_jacobi = block_jacobi;
  auto model = build_model(c);
  EXPECT_TRUE(model);
  MechanicalState state = make_state(*model);
  for (int i = 0; i < steps; ++i) EXPECT_TRUE(step(*model, state));
  return state;
}

TEST(Determinism, ResultsDoNotDependOnTheThreadCount) {
  const mesh::Mesh& m = liver(mesh::LiverResolution::kMedium);
  const MechanicalState one = run_with_threads(m, 1, 5);
  const MechanicalState two = run_with_threads(m, 2, 5);
  EXPECT_TRUE(one.x == two.x);  // bitwise
  EXPECT_TRUE(one.v == two.v);
  // Three threads split the solve's chunks unevenly, each part with its own exchange copies.
  const MechanicalState three = run_with_threads(m, 3, 5);
  EXPECT_TRUE(one.x == three.x);
  EXPECT_TRUE(one.v == three.v);
  EXPECT_GT((one.x - run_with_threads(m, 1, 0).x).norm(), 0.0);  // it did move
}

TEST(Determinism, ResultsDoNotDependOnTheThreadCountWithoutPreconditioner) {
  // SOFA's default CG, where the update rounds the residual for the product as it goes.
  const mesh::Mesh& m = liver(mesh::LiverResolution::kMedium);
  const MechanicalState one = run_with_threads(m, 1, 5, false);
  for (int threads : {2, 3}) {
    const MechanicalState many = run_with_threads(m, threads, 5, false);
    EXPECT_TRUE(one.x == many.x) << threads << " threads";
    EXPECT_TRUE(one.v == many.v) << threads << " threads";
  }
  EXPECT_FALSE(one.x == run_with_threads(m, 1, 5).x);  // the preconditioner changed the iterates
}

TEST(SofaLiver, TheSofaDemoMeshRunsWithItsSettings) {
  // liver.scn: dt 0.02, gravity −9.81 y, implicit Euler (Rayleigh 0.1/0.1), CG 25 it,
  // co-rotational FEM E 3000 ν 0.3, DiagonalMass density 1, fixed 3 39 64 (scene units).
  auto read = mesh::read_mesh(HOF_ANCHORS_DIR "/sofa/mesh/liver.msh");
  ASSERT_TRUE(read) << read.error().to_string();
  ModelConfig c;
  c.positions = read->mesh.nodes;
  c.tets = read->mesh.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1.0;
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{3000.0, 0.3, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  c.fixed.push_back(FixedConstraintConfig{"fixed", {3, 39, 64}, std::nullopt, false, {true, true, true}});
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.linear.tolerance = c.linear.threshold = 1e-9;
  c.dt_s = 0.02;
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  // SOFA reports the liver's mass as 36.56 (its volume in scene units at density 1).
  EXPECT_NEAR(model->total_mass_kg(), 36.56, 0.01);
  MechanicalState state = make_state(*model);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
  EXPECT_LT(state.position(10).y(), model->rest_positions[10].y());  // it sags under gravity
  EXPECT_EQ(state.position(3), model->rest_positions[3]);            // fixed nodes stay
}

}  // namespace
}  // namespace hof::mechanics
