// The integrators (src/hof/mechanics/detail/*: explicit Euler, RK4, implicit Euler, static)
// through step(): energy behaviour of each ODE solver on an undamped vibrating block, the
// critical time step of explicit Euler, and divergence reporting.

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/step.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;

// A free 0.1 m block of linear FEM (a linear system, so energy statements are exact), with
// lumped mass, no gravity, released from a 2% stretch along x.
ModelConfig vibrating_block(OdeSolverKind solver, double dt, FemMethod method = FemMethod::kSmall) {
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
  fem.tetrahedron_fem = TetrahedronFemConfig{10000.0, 0.3, method, {}, {}};
  c.force_fields.push_back(fem);
  c.ode.kind = solver;
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  c.dt_s = dt;
  return c;
}

void stretch(const MechanicalModel& model, MechanicalState& state) {
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    state.x[3 * static_cast<Eigen::Index>(n)] = 1.02 * model.rest_positions[n].x();
  }
}

double total_energy(const MechanicalModel& model, const MechanicalState& state) {
  return kinetic_energy(model, state) + potential_energy(model, state);
}

// Highest natural frequency ω_max of M⁻¹K: explicit schemes are stable for h < 2/ω_max.
double highest_frequency(const MechanicalModel& model) {
  MechanicalState state = make_state(model);
  compute_forces(model, state, state.x, state.v, state.f);
  state.work->system = model.pattern;
  detail::assemble_system(model, state, 0.0, 1.0);
  const Eigen::MatrixXd k = state.work->system.to_dense();
  Eigen::VectorXd inv_sqrt_m(k.rows());
  for (Eigen::Index i = 0; i < k.rows(); ++i)
    inv_sqrt_m[i] = 1.0 / std::sqrt(model.node_mass_kg[static_cast<std::size_t>(i / 3)]);
  const Eigen::MatrixXd scaled = inv_sqrt_m.asDiagonal() * k * inv_sqrt_m.asDiagonal();
  return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled).eigenvalues().maxCoeff());
}

double critical_dt() {
  auto model = build_model(vibrating_block(OdeSolverKind::kEulerExplicit, 1e-4));
  EXPECT_TRUE(model);
  return 2.0 / highest_frequency(*model);
}

TEST(Dynamics, SymplecticEulerKeepsEnergyBoundedOverTenThousandSteps) {
  const double dt = 0.5 * critical_dt();
  auto model = build_model(vibrating_block(OdeSolverKind::kEulerExplicit, dt));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  stretch(*model, state);
  const double e0 = total_energy(*model, state);
  ASSERT_GT(e0, 0.0);
  double early_max = 0.0, late_max = 0.0, lowest = e0;
  for (int i = 0; i < 10000; ++i) {
    ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
    const double e = total_energy(*model, state);
    if (i < 1000) early_max = std::max(early_max, e);
    if (i >= 9000) late_max = std::max(late_max, e);
    lowest = std::min(lowest, e);
  }
  // Symplectic Euler conserves a modified energy: the true energy oscillates within a band
  // of order h·ω around e0 and does not drift.
  EXPECT_LT(late_max, 1.01 * early_max);
  EXPECT_LT(early_max, 1.5 * e0);
  EXPECT_GT(lowest, 0.5 * e0);
}

TEST(Dynamics, ImplicitEulerEnergyDecaysMonotonically) {
  auto model = build_model(vibrating_block(OdeSolverKind::kEulerImplicit, 5.0 * critical_dt()));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  stretch(*model, state);
  double previous = total_energy(*model, state);
  const double e0 = previous;
  for (int i = 0; i < 500; ++i) {
    ASSERT_TRUE(step(*model, state));
    const double e = total_energy(*model, state);
    EXPECT_LE(e, previous * (1.0 + 1e-12) + 1e-14 * e0) << "step " << i;  // round-off floor
    previous = e;
  }
  EXPECT_LT(previous, 0.5 * e0);  // numerical damping has taken energy out
}

TEST(Dynamics, RungeKutta4TracksTheEnergyClosely) {
  auto model = build_model(vibrating_block(OdeSolverKind::kRungeKutta4, 0.2 * critical_dt()));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  stretch(*model, state);
  const double e0 = total_energy(*model, state);
  for (int i = 0; i < 2000; ++i) ASSERT_TRUE(step(*model, state));
  EXPECT_NEAR(total_energy(*model, state), e0, 0.01 * e0);
}

TEST(Dynamics, ExplicitEulerBeyondCriticalStepIsReportedAsDiverged) {
  // Co-rotational, so that the blow-up shows as runaway speed rather than inverted elements
  // (the critical step is the same at rest).
  auto model = build_model(vibrating_block(OdeSolverKind::kEulerExplicit, 1.2 * critical_dt(), FemMethod::kLarge));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  stretch(*model, state);
  bool diverged = false;
  for (int i = 0; i < 20000 && !diverged; ++i) diverged = !step(*model, state);
  ASSERT_TRUE(diverged);
  EXPECT_TRUE(state.divergence.diverged);
  EXPECT_NE(state.divergence.component.find("EulerExplicitSolver"), std::string::npos);
  EXPECT_NE(state.divergence.reason.find("unstable"), std::string::npos) << state.divergence.reason;
  EXPECT_EQ(state.divergence.fault.kind, FaultKind::kRunawayNode);
  EXPECT_GT(state.divergence.fault.value, model->max_speed_m_per_s);
  EXPECT_TRUE(state.x.allFinite());
  EXPECT_TRUE(state.v.allFinite());
  // It stays stopped, and a reset brings it back to rest.
  EXPECT_FALSE(step(*model, state));
  reset(*model, state);
  EXPECT_FALSE(state.divergence.diverged);
  EXPECT_TRUE(step(*model, state));
}

TEST(Dynamics, BelowCriticalStepExplicitEulerStaysStable) {
  auto model = build_model(vibrating_block(OdeSolverKind::kEulerExplicit, 0.9 * critical_dt()));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  stretch(*model, state);
  for (int i = 0; i < 5000; ++i) ASSERT_TRUE(step(*model, state)) << "step " << i;
}

TEST(Dynamics, InvertedLinearElementUnderExtremeLoadIsReported) {
  ModelConfig c = vibrating_block(OdeSolverKind::kEulerImplicit, 0.01);
  FixedConstraintConfig base;
  base.box = std::make_pair(Vec3(-1, -1, -1), Vec3(1, 1, 1e-9));
  c.fixed.push_back(base);
  ForceFieldConfig crush;
  crush.name = "crush";
  crush.constant_force = ConstantForceConfig{{26}, {Vec3(0, 0, -1e5)}, std::nullopt};  // top corner
  c.force_fields.push_back(crush);
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  bool diverged = false;
  for (int i = 0; i < 10 && !diverged; ++i) diverged = !step(*model, state);
  ASSERT_TRUE(diverged);
  EXPECT_NE(state.divergence.component.find("TetrahedronFEMForceField 'FEM'"), std::string::npos);
  EXPECT_NE(state.divergence.reason.find("inverted"), std::string::npos);
  EXPECT_EQ(state.divergence.fault.kind, FaultKind::kInvertedElement);
  EXPECT_EQ(state.divergence.fault.field, 0);
  EXPECT_NE(state.divergence.reason.find(fmt::format("tetrahedron {} is", state.divergence.fault.index)),
            std::string::npos);
  EXPECT_TRUE(state.x.allFinite());
}

TEST(Dynamics, BadParametersAreClearErrors) {
  ModelConfig c = vibrating_block(OdeSolverKind::kEulerImplicit, 0.01);
  c.force_fields[0].tetrahedron_fem->poisson_ratio = 0.5;
  auto model = build_model(c);
  ASSERT_FALSE(model);
  EXPECT_NE(model.error().message.find("TetrahedronFEMForceField 'FEM': poissonRatio"), std::string::npos);
  c = vibrating_block(OdeSolverKind::kEulerImplicit, -0.01);
  EXPECT_FALSE(build_model(c));
  c = vibrating_block(OdeSolverKind::kEulerImplicit, 0.01);
  FixedConstraintConfig bad;
  bad.indices = {1000};
  c.fixed.push_back(bad);
  model = build_model(c);
  ASSERT_FALSE(model);
  EXPECT_NE(model.error().message.find("index 1000 is out of range"), std::string::npos);
}

}  // namespace
}  // namespace hof::mechanics
