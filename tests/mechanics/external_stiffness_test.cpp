// MechanicalState::external_stiffness (the contact springs' stiffness in the implicit solve,
// detail/implicit_euler.cpp): a block held to its rest place by stiff springs at every node,
// against the scalar recurrence of implicit Euler, with the direct solver, CG and a reused
// matrix; forces alone at that stiffness blow up; held nodes stay held.

#include <gtest/gtest.h>

#include <cmath>

#include "hof/mechanics/step.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;

// A free 0.1 m block of linear FEM (small strain: a rigid translation strains nothing), no
// gravity.
ModelConfig block(LinearSolverKind solver, double dt) {
  const auto box = box_mesh(2, 2, 2, Vec3(0.1, 0.1, 0.1));
  ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.gravity_m_per_s2 = Vec3::Zero();
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{10000.0, 0.3, FemMethod::kSmall, {}, {}};
  c.force_fields.push_back(fem);
  c.ode.kind = OdeSolverKind::kEulerImplicit;
  c.linear.kind = solver;
  c.linear.iterations = 1000;
  c.linear.tolerance = 1e-24;
  c.linear.threshold = 1e-30;
  c.linear.mixed_precision = false;
  c.dt_s = dt;
  return c;
}

// Springs of stiffness k per unit mass-weight to each node's rest place, along `axis`: the
// force −k m_i/m̄ (x_i − X_i)·axis and its stiffness, as a coupling writes them before a step.
void load_springs(const MechanicalModel& model, MechanicalState& state, double k_per_kg, const Vec3& axis,
                  bool with_stiffness) {
  state.external_stiffness.clear();
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const double k = k_per_kg * model.node_mass_kg[i];
    const auto at = 3 * static_cast<Eigen::Index>(i);
    const double stretch = (state.x.segment<3>(at) - model.rest_positions[i]).dot(axis);
    state.external_force.segment<3>(at) = -k * stretch * axis;
    if (with_stiffness) state.external_stiffness.push_back({static_cast<std::int32_t>(i), k * axis * axis.transpose()});
  }
}

// Every node moved by u along the axis: a rigid translation, which the FEM does not resist,
// so each node follows implicit Euler on ü = −ω² u: (1 + h²ω²) Δv = −h ω² u − h² ω² v.
void expect_scalar_recurrence(LinearSolverKind solver, int reuse, bool mixed_precision = false,
                              double tolerance_m = 1e-9) {
  const double h = 0.02, omega2 = 1e6;  // h ω = 20: explicit schemes would need h < 2 ms
  ModelConfig config = block(solver, h);
  config.ode.matrix_reuse_steps = reuse;
  config.linear.mixed_precision = mixed_precision;
  // Single-precision products stop improving near 1e-14 of |b|²: iterating on would only stir.
  if (mixed_precision) config.linear.tolerance = 1e-14;
  auto model = build_model(config);
  ASSERT_TRUE(model) << model.error().message;
  MechanicalState state = make_state(*model);
  const Vec3 axis = Vec3(1.0, 2.0, -0.5).normalized();
  double u = 0.003, v = 0.0;
  for (std::size_t i = 0; i < model->node_count(); ++i)
    state.x.segment<3>(3 * static_cast<Eigen::Index>(i)) += u * axis;
  for (int s = 0; s < 40; ++s) {
    load_springs(*model, state, omega2, axis, true);
    ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
    const double dv = (-h * omega2 * u - h * h * omega2 * v) / (1.0 + h * h * omega2);
    v += dv;
    u += h * v;
    for (std::size_t i = 0; i < model->node_count(); ++i) {
      const Vec3 displacement = state.position(static_cast<std::int32_t>(i)) - model->rest_positions[i];
      ASSERT_NEAR(displacement.dot(axis), u, tolerance_m) << "step " << s << " node " << i;
      ASSERT_NEAR((displacement - displacement.dot(axis) * axis).norm(), 0.0, tolerance_m);
    }
  }
  EXPECT_LT(std::abs(u), 0.003);  // decays (implicit Euler's numerical damping)
}

TEST(ExternalStiffness, DirectSolverFollowsImplicitEulerOfTheSprings) {
  expect_scalar_recurrence(LinearSolverKind::kSparseLdlt, 1);
}

TEST(ExternalStiffness, ConjugateGradientFollowsImplicitEulerOfTheSprings) {
  expect_scalar_recurrence(LinearSolverKind::kConjugateGradient, 1);
}

TEST(ExternalStiffness, MixedPrecisionConjugateGradientFollowsItToSinglePrecision) {
  // The single-precision copy of A gets the springs (its products round to 1e-7 relative, and the errors of 40 steps
  // add up; the displacement is 3 mm): within 0.1% of it. 1e-6 m was too tight for every compiler — clang's
  // x86-64-v3 build (FMA contraction) lands at 1.02e-6 m.
  expect_scalar_recurrence(LinearSolverKind::kConjugateGradient, 1, true, 3e-6);
}

TEST(ExternalStiffness, AReusedMatrixTakesTheLastStepsSpringsOut) {
  expect_scalar_recurrence(LinearSolverKind::kSparseLdlt, 3);
  expect_scalar_recurrence(LinearSolverKind::kConjugateGradient, 4);
}

TEST(ExternalStiffness, TheSameForcesWithoutTheirStiffnessBlowUp) {
  auto model = build_model(block(LinearSolverKind::kSparseLdlt, 0.02));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  const Vec3 axis = Vec3::UnitY();
  for (std::size_t i = 0; i < model->node_count(); ++i) state.x[3 * static_cast<Eigen::Index>(i) + 1] += 0.003;
  double largest = 0.0;
  for (int s = 0; s < 20; ++s) {
    load_springs(*model, state, 1e6, axis, false);
    if (!step(*model, state)) break;
    for (std::size_t i = 0; i < model->node_count(); ++i) {
      largest = std::max(largest, (state.position(static_cast<std::int32_t>(i)) - model->rest_positions[i]).norm());
    }
  }
  EXPECT_TRUE(state.divergence.diverged || largest > 0.1) << largest;
}

TEST(ExternalStiffness, HeldNodesStayHeld) {
  ModelConfig config = block(LinearSolverKind::kSparseLdlt, 0.01);
  FixedConstraintConfig fixed;
  fixed.name = "base";
  fixed.indices = {0, 1, 2};
  config.fixed.push_back(fixed);
  auto model = build_model(config);
  ASSERT_TRUE(model) << model.error().message;
  MechanicalState state = make_state(*model);
  for (int s = 0; s < 10; ++s) {
    state.external_stiffness.clear();
    state.external_force.setZero();
    for (std::int32_t i = 0; i < 4; ++i) {
      state.external_force.segment<3>(3 * i) = Vec3(1.0, -2.0, 0.5);
      state.external_stiffness.push_back({i, 1e5 * Mat3::Identity()});
    }
    ASSERT_TRUE(step(*model, state));
  }
  for (std::int32_t i = 0; i < 3; ++i) EXPECT_EQ(state.position(i), model->rest_positions[static_cast<std::size_t>(i)]);
  EXPECT_GT((state.position(3) - model->rest_positions[3]).norm(), 0.0);
}

TEST(ExternalStiffness, NoEntriesLeaveTheStepBitForBitAsBefore) {
  // Two states of the same model, one of which had springs for a while and then none: from the
  // same positions their steps agree exactly once the entries are gone and the matrix is fresh.
  auto model = build_model(block(LinearSolverKind::kSparseLdlt, 0.01));
  ASSERT_TRUE(model);
  MechanicalState plain = make_state(*model);
  MechanicalState sprung = make_state(*model);
  for (auto* s : {&plain, &sprung}) s->x[0] += 0.001;
  sprung.external_stiffness.push_back({0, 1e4 * Mat3::Identity()});
  ASSERT_TRUE(step(*model, sprung));
  sprung.external_stiffness.clear();
  sprung.x = plain.x;
  sprung.v = plain.v;
  for (int s = 0; s < 5; ++s) {
    ASSERT_TRUE(step(*model, plain));
    ASSERT_TRUE(step(*model, sprung));
  }
  EXPECT_EQ(plain.x, sprung.x);
  EXPECT_EQ(plain.v, sprung.v);
}

}  // namespace
}  // namespace hof::mechanics
