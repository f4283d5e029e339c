// step() (step.cpp) and its integrators, each against the exact motion it must give a body in
// free fall (a uniform field, no elastic force: every scheme's own recurrence is solvable in
// closed form), and the bookkeeping every scheme shares: time and step count, a diverged state
// that no longer moves until reset, and reset back to rest.

#include "hof/mechanics/step.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;

constexpr double kGravity = -9.81;  // m/s², along z

ModelConfig falling_block(OdeSolverKind kind, double dt) {
  const auto box = box_mesh(2, 2, 2, Vec3(0.05, 0.05, 0.05));
  ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.gravity_m_per_s2 = Vec3(0.0, 0.0, kGravity);
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{5000.0, 0.3, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  c.ode.kind = kind;
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  c.dt_s = dt;
  return c;
}

// The drop of every node after n steps of h from rest, as each scheme's recurrence gives it
// for a constant acceleration g (a rigid translation leaves the elastic force at zero):
//   symplectic Euler and implicit Euler  v_{k+1} = v_k + h g, x_{k+1} = x_k + h v_{k+1}
//                                        → x_n = g h² n (n + 1) / 2
//   explicit (non-symplectic) Euler      x_{k+1} = x_k + h v_k → x_n = g h² n (n − 1) / 2
//   RK4                                  exact for a polynomial of degree 2 → g (n h)² / 2
double expected_drop(OdeSolverKind kind, bool symplectic, double h, int n) {
  const double steps = n;
  switch (kind) {
    case OdeSolverKind::kEulerExplicit:
      return symplectic ? 0.5 * kGravity * h * h * steps * (steps + 1) : 0.5 * kGravity * h * h * steps * (steps - 1);
    case OdeSolverKind::kEulerImplicit:
      return 0.5 * kGravity * h * h * steps * (steps + 1);
    case OdeSolverKind::kRungeKutta4:
      return 0.5 * kGravity * (steps * h) * (steps * h);
    case OdeSolverKind::kStatic:
      break;
  }
  return 0.0;
}

struct FreeFallCase {
  OdeSolverKind kind;
  bool symplectic;
  const char* name;
};

class FreeFall : public ::testing::TestWithParam<FreeFallCase> {};

TEST_P(FreeFall, EveryNodeFollowsTheSchemesExactRecurrence) {
  const FreeFallCase& param = GetParam();
  ModelConfig c = falling_block(param.kind, 0.004);
  c.ode.symplectic = param.symplectic;
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().message;
  MechanicalState state = make_state(*model);
  constexpr int kSteps = 50;
  for (int k = 0; k < kSteps; ++k) ASSERT_TRUE(step(*model, state));
  const double drop = expected_drop(param.kind, param.symplectic, c.dt_s, kSteps);
  ASSERT_LT(drop, -0.01);  // it fell far enough for the comparison to mean something
  // Non-symplectic explicit Euler amplifies every oscillation (it is unstable for an undamped
  // spring at any step), so the round-off of the elastic force of a rigid translation grows to
  // ~1e-9 m over the run; the stable schemes keep it at round-off.
  const double tolerance = param.kind == OdeSolverKind::kEulerExplicit && !param.symplectic ? 1e-8 : 1e-12;
  for (std::size_t n = 0; n < model->node_count(); ++n) {
    const Vec3 moved = state.position(static_cast<std::int32_t>(n)) - model->rest_positions[n];
    EXPECT_NEAR(moved.z(), drop, 1e-9 * std::abs(drop) + tolerance) << "node " << n;
    EXPECT_NEAR(moved.x(), 0.0, tolerance);
    EXPECT_NEAR(moved.y(), 0.0, tolerance);
  }
  EXPECT_NEAR(state.time_s, kSteps * c.dt_s, 1e-12);
  EXPECT_EQ(state.steps, kSteps);
}

INSTANTIATE_TEST_SUITE_P(Integrators, FreeFall,
                         ::testing::Values(FreeFallCase{OdeSolverKind::kEulerExplicit, true, "SymplecticEuler"},
                                           FreeFallCase{OdeSolverKind::kEulerExplicit, false, "ExplicitEuler"},
                                           FreeFallCase{OdeSolverKind::kEulerImplicit, true, "ImplicitEuler"},
                                           FreeFallCase{OdeSolverKind::kRungeKutta4, true, "RungeKutta4"}),
                         [](const ::testing::TestParamInfo<FreeFallCase>& p) { return p.param.name; });

TEST(Step, TheStaticSolverFindsTheEquilibriumOfAHeldBlockInOneStep) {
  ModelConfig c = falling_block(OdeSolverKind::kStatic, 0.01);
  FixedConstraintConfig bottom;
  for (std::size_t n = 0; n < c.positions.size(); ++n)
    if (c.positions[n].z() == 0.0) bottom.indices.push_back(static_cast<std::int32_t>(n));
  c.fixed.push_back(bottom);
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().message;
  MechanicalState state = make_state(*model);
  ASSERT_TRUE(step(*model, state));
  // At equilibrium the force on every free node is zero (to the Newton tolerance), and the
  // block has sagged under its own weight.
  for (std::size_t d = 0; d < static_cast<std::size_t>(state.f.size()); ++d) EXPECT_LT(std::abs(state.f[d]), 1e-5);
  double top = 0.0;
  for (std::size_t n = 0; n < model->node_count(); ++n)
    top = std::max(top, state.position(static_cast<std::int32_t>(n)).z());
  EXPECT_LT(top, 0.05);
  EXPECT_LT(state.stats.residual_force_n, c.ode.newton_residual_tolerance_n);
}

TEST(Step, ADivergedStateStaysWhereItWasUntilReset) {
  // Explicit Euler far beyond its critical step on a stiff block, pulled apart.
  ModelConfig c = falling_block(OdeSolverKind::kEulerExplicit, 0.05);
  c.force_fields[0].tetrahedron_fem->young_modulus_pa = 1e7;
  auto model = build_model(c);
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  for (std::size_t n = 0; n < model->node_count(); ++n) state.x[3 * static_cast<Eigen::Index>(n)] *= 1.05;
  int steps = 0;
  while (step(*model, state) && steps < 1000) ++steps;
  ASSERT_TRUE(state.divergence.diverged);
  const Eigen::VectorXd x = state.x;
  const std::int64_t count = state.steps;
  EXPECT_FALSE(step(*model, state));
  EXPECT_EQ(state.x, x);
  EXPECT_EQ(state.steps, count);
  EXPECT_TRUE(state.x.allFinite());

  reset(*model, state);
  EXPECT_FALSE(state.divergence.diverged);
  EXPECT_EQ(state.steps, 0);
  EXPECT_EQ(state.time_s, 0.0);
  for (std::size_t n = 0; n < model->node_count(); ++n)
    EXPECT_EQ(state.position(static_cast<std::int32_t>(n)), model->rest_positions[n]);
  EXPECT_EQ(state.v.squaredNorm(), 0.0);
}

TEST(Step, KineticEnergyIsHalfMassTimesSpeedSquared) {
  auto model = build_model(falling_block(OdeSolverKind::kEulerImplicit, 0.01));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  double mass = 0.0;
  for (double m : model->node_mass_kg) mass += m;
  EXPECT_NEAR(mass, 1000.0 * 0.05 * 0.05 * 0.05, 1e-12);
  for (std::size_t n = 0; n < model->node_count(); ++n) state.v[3 * static_cast<Eigen::Index>(n) + 1] = 2.0;
  EXPECT_NEAR(kinetic_energy(*model, state), 0.5 * mass * 4.0, 1e-12);
}

}  // namespace
}  // namespace hof::mechanics
