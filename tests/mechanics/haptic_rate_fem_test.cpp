// The mechanics at the haptic rate (issue 17): co-rotational FEM on the medium liver with
// implicit Euler at dt = 1 ms. A warm-started CG with fewer iterations must solve each step at
// least as well as 25 iterations from zero (SOFA's default), measured against an exact sparse
// LDLᵀ solve of the very same step.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <initializer_list>
#include <tuple>
#include <utility>

#include "hof/mechanics/model_parameters.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/liver_generator.h"
#include "physiological_liver.h"

namespace hof::mechanics {
namespace {

using testing::make_solver;
using testing::Solver;
using testing::step_error;

const mesh::Mesh& medium_liver() {
  static const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kMedium);
  return liver;
}

// Physiological liver, held at its lowest nodes, co-rotational FEM, implicit Euler at the
// haptic period.
ModelConfig haptic_rate_config(const mesh::Mesh& liver) { return testing::physiological_liver_config(liver); }

// Nodes within 1 cm of the top of the liver, a fingertip's patch; on a mesh too coarse for
// that, the four nearest the top.
std::vector<std::int32_t> pressed_patch(const mesh::Mesh& liver) {
  const Vec3 top = *std::ranges::max_element(liver.nodes, {}, [](const Vec3& p) { return p.z(); });
  std::vector<std::int32_t> patch(liver.nodes.size());
  for (std::size_t i = 0; i < patch.size(); ++i) patch[i] = static_cast<std::int32_t>(i);
  std::ranges::sort(patch, {}, [&](std::int32_t i) { return (liver.nodes[static_cast<std::size_t>(i)] - top).norm(); });
  std::size_t within = 0;
  while (within < patch.size() && (liver.nodes[static_cast<std::size_t>(patch[within])] - top).norm() < 0.01) ++within;
  patch.resize(std::max<std::size_t>(within, 4));
  return patch;
}

void expect_haptic_rate_cg_at_least_as_good_as_cold_cg(const mesh::Mesh& liver) {
  ModelConfig base = haptic_rate_config(liver);
  const std::vector<std::int32_t> patch = pressed_patch(liver);
  ASSERT_GE(patch.size(), 3u);

  ModelConfig exact_config = base;
  exact_config.linear.kind = LinearSolverKind::kSparseLdlt;
  ModelConfig cold_config = base;  // SOFA's CGLinearSolver defaults: 25 iterations from zero
  cold_config.linear.iterations = 25;
  cold_config.linear.tolerance = 1e-30;
  cold_config.linear.threshold = 1e-30;
  ModelConfig warm_config = cold_config;
  use_haptic_rate_solver(warm_config.linear, warm_config.ode, liver.nodes.size());
  Solver exact = make_solver(exact_config);
  Solver cold = make_solver(cold_config);
  Solver warm = make_solver(warm_config);

  // A press ramping to 2 N over 0.1 s, then held: the warm-started solver follows its own
  // trajectory (its guess is its own history); every 10 steps the same step is also made by
  // an exact solve and by 25 cold iterations from its state.
  double worst_warm = 0.0, worst_cold = 0.0, largest_motion = 0.0;
  int samples = 0;
  const Eigen::VectorXd rest = warm.state.x;
  for (int n = 0; n < 160; ++n) {
    const double force_n = 2.0 * std::min(1.0, (n + 1) * 1e-3 / 0.1);
    warm.state.external_force.setZero();
    for (std::int32_t i : patch) warm.state.external_force[3 * i + 2] = -force_n / static_cast<double>(patch.size());
    exact.state.external_force = warm.state.external_force;
    cold.state.external_force = warm.state.external_force;
    if (n % 10 == 9) {
      const Eigen::VectorXd x0 = warm.state.x, v0 = warm.state.v;
      exact.state.x = cold.state.x = x0;
      exact.state.v = cold.state.v = v0;
      ASSERT_TRUE(step(exact.model, exact.state));
      ASSERT_TRUE(step(cold.model, cold.state));
      ASSERT_TRUE(step(warm.model, warm.state));
      worst_warm = std::max(worst_warm, step_error(v0, warm.state.v, exact.state.v));
      worst_cold = std::max(worst_cold, step_error(v0, cold.state.v, exact.state.v));
      ++samples;
    } else {
      ASSERT_TRUE(step(warm.model, warm.state));
    }
    largest_motion = std::max(largest_motion, (warm.state.x - rest).cwiseAbs().maxCoeff());
  }
  ASSERT_EQ(samples, 16);
  // The press moved the liver (else every solver is trivially exact) and cold CG is inexact.
  EXPECT_GT(largest_motion, 1e-4);
  EXPECT_GT(worst_cold, 1e-3);
  std::printf(
      "%zu nodes, worst relative step error: warm two-level %d iterations (matrix every %d steps) %.3e, cold 25 "
      "iterations %.3e\n",
      liver.nodes.size(), warm_config.linear.iterations, warm_config.ode.matrix_reuse_steps, worst_warm, worst_cold);
  EXPECT_LE(worst_warm, worst_cold);
}

TEST(HapticRateFem, WarmStartedCgSolvesEachStepAtLeastAsWellAsTwentyFiveIterationsFromZero) {
  expect_haptic_rate_cg_at_least_as_good_as_cold_cg(medium_liver());
}

// On a small liver 25 cold iterations all but solve the step: the haptic-rate mode then makes
// one iteration more (haptic_rate_cg_iterations).
TEST(HapticRateFem, OnTheSimpleLiverTooTheHapticRateCgIsAtLeastAsGoodAsTwentyFiveColdIterations) {
  expect_haptic_rate_cg_at_least_as_good_as_cold_cg(*mesh::generate_liver(mesh::LiverResolution::kSimple));
}

// A warm start changes where CG begins, not what it converges to: run to convergence in
// double precision, warm and cold reach the exact solution of every step, also after the
// load (and so the solution) changed direction.
TEST(HapticRateFem, WarmStartConvergesToTheExactSolve) {
  // The simple liver: convergence, not speed, is the point (and it stays quick under ASan).
  static const mesh::Mesh simple = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  ModelConfig base = haptic_rate_config(simple);
  base.linear.mixed_precision = false;
  base.linear.iterations = 2000;
  base.linear.tolerance = 1e-24;
  base.linear.threshold = 1e-30;
  ModelConfig exact_config = base;
  exact_config.linear.kind = LinearSolverKind::kSparseLdlt;
  ModelConfig warm_config = base;
  warm_config.linear.warm_start = true;
  Solver exact = make_solver(exact_config);
  Solver warm = make_solver(warm_config);
  const std::vector<std::int32_t> patch = pressed_patch(simple);
  ASSERT_FALSE(patch.empty());
  for (int n = 0; n < 6; ++n) {
    const double force_n = n < 3 ? 2.0 : -1.0;
    for (Solver* s : {&exact, &warm}) {
      s->state.external_force.setZero();
      for (std::int32_t i : patch) s->state.external_force[3 * i + 2] = -force_n / static_cast<double>(patch.size());
    }
    const Eigen::VectorXd v0 = exact.state.v;
    ASSERT_TRUE(step(exact.model, exact.state));
    ASSERT_TRUE(step(warm.model, warm.state));
    EXPECT_LT(step_error(v0, warm.state.v, exact.state.v), 1e-6) << "step " << n;
    EXPECT_GT(warm.state.stats.linear_iterations, 0) << "step " << n;
    warm.state.x = exact.state.x;  // the same start for the next step
    warm.state.v = exact.state.v;
  }
}

// The haptic-rate settings are parameters like any other (projects' <set>, the window, the
// command seam): named, range-checked, and the config unchanged on a refusal.
TEST(HapticRateFem, WarmStartAndMatrixReuseAreParameters) {
  ModelConfig c = haptic_rate_config(medium_liver());
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kWarmStart}, 1.0));
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kOdeSolver, 0}, ParameterId::kMatrixReuseSteps}, 3.0));
  EXPECT_TRUE(c.linear.warm_start);
  EXPECT_EQ(c.ode.matrix_reuse_steps, 3);
  EXPECT_EQ(*get_parameter(c, ParameterRef{{ComponentKind::kOdeSolver, 0}, ParameterId::kMatrixReuseSteps}), 3.0);
  EXPECT_EQ(*get_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kWarmStart}), 1.0);
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kIterations}, 7.0));
  EXPECT_EQ(c.linear.iterations, 7);
  EXPECT_EQ(c.ode.matrix_reuse_steps, 3);  // one integer parameter does not write another
  const ParameterRef reuse{{ComponentKind::kOdeSolver, 0}, ParameterId::kMatrixReuseSteps};
  const ParameterRef warm{{ComponentKind::kLinearSolver, 0}, ParameterId::kWarmStart};
  for (const auto& [ref, value] :
       {std::pair{reuse, 0.0}, std::pair{reuse, 2.5}, std::pair{warm, 2.0}, std::pair{warm, 0.5}}) {
    const ModelConfig before = c;
    const std::string_view parameter = parameter_name(ref.id);
    auto refused = set_parameter(c, ref, value);
    ASSERT_FALSE(refused) << parameter << " = " << value;
    EXPECT_NE(refused.error().message.find(parameter), std::string::npos) << refused.error().message;
    EXPECT_EQ(c.ode.matrix_reuse_steps, before.ode.matrix_reuse_steps);
    EXPECT_EQ(c.linear.warm_start, before.linear.warm_start);
  }
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kWarmStart}, 0.0));
  EXPECT_FALSE(c.linear.warm_start);
}

// A real-time session sets its bodies' threads when it starts (one on two cores) and back when
// it stops, between steps, with a reused matrix and a warm start in flight: the steps must not
// notice. Two threads and one, switched every few steps, against one throughout, bit for bit.
TEST(HapticRateFem, ChangingTheThreadsBetweenStepsChangesNoResult) {
  ModelConfig c = haptic_rate_config(medium_liver());
  c.threads = 0;
  use_haptic_rate_solver(c.linear, c.ode, c.positions.size());
  c.ode.matrix_reuse_steps = 2;  // a reused matrix in flight too
  Solver fixed = make_solver(c);
  Solver switched = make_solver(c);
  set_threads(fixed.model, fixed.state, 1);
  const std::vector<std::int32_t> patch = pressed_patch(medium_liver());
  for (int k = 0; k < 12; ++k) {
    if (k % 3 == 0) set_threads(switched.model, switched.state, k % 2 == 0 ? 2 : 1);
    for (Solver* s : {&fixed, &switched}) {
      s->state.external_force.setZero();
      for (std::int32_t i : patch) s->state.external_force[3 * i + 2] = -0.5 / static_cast<double>(patch.size());
      ASSERT_TRUE(step(s->model, s->state));
    }
    ASSERT_EQ(fixed.state.x, switched.state.x) << "step " << k;
    ASSERT_EQ(fixed.state.v, switched.state.v) << "step " << k;
  }
}

}  // namespace
}  // namespace hof::mechanics
