// The conjugate-gradient solve's two-level preconditioner (mechanics/coarse_correction.h):
// diagonal Jacobi plus an exact solve on the rigid motions of a few dozen aggregates of nodes.
// It must stay a preconditioner (CG converges to the exact solve, also with a coarse matrix
// formed at another shape), remove the smooth error plain CG leaves, and cope with held and
// tiny bodies.

#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>
#include <utility>

#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/model_parameters.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/liver_generator.h"
#include "physiological_liver.h"

namespace hof::mechanics {
namespace {

using testing::make_solver;
using testing::physiological_liver_config;
using testing::Solver;
using testing::step_error;

// A downward load on the nodes within 1 cm of the top.
void press(const mesh::Mesh& liver, MechanicalState& state, double force_n) {
  const Vec3 top = *std::ranges::max_element(liver.nodes, {}, [](const Vec3& p) { return p.z(); });
  std::vector<std::int32_t> patch;
  for (std::size_t i = 0; i < liver.nodes.size(); ++i) {
    if ((liver.nodes[i] - top).norm() < 0.01) patch.push_back(static_cast<std::int32_t>(i));
  }
  state.external_force.setZero();
  for (std::int32_t i : patch) state.external_force[3 * i + 2] = -force_n / static_cast<double>(patch.size());
}

TEST(SystemAssembly, TheSinglePrecisionCopyHoldsHeldNodesAsTheDoubleMatrixDoes) {
  // Nodes held on every axis (cleared a whole node at a time) and nodes held on one axis only
  // (a PartialFixedConstraint): the single-precision system the CG reads must be the double
  // one rounded, with exact identity rows and columns for every held degree of freedom.
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  ModelConfig c = physiological_liver_config(liver);
  FixedConstraintConfig sliding;
  sliding.directions = {false, false, true};
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(liver.nodes.size()); i += 7) sliding.indices.push_back(i);
  c.fixed.push_back(sliding);
  c.linear.mixed_precision = true;
  Solver s = make_solver(c);
  ASSERT_GT(s.model.fixed_dofs.size(), 3u);
  press(liver, s.state, 2.0);
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(step(s.model, s.state));  // a deformed, rotated shape
  detail::assemble_system(s.model, s.state, 1.1, 2e-6, detail::AssemblyTarget::kSolver);
  BlockSparseMatrix& a = s.state.work->system;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(a.block_rows());
  Eigen::MatrixXd single = Eigen::MatrixXd::Zero(n, n);
  for (std::int32_t r = 0; r < a.block_rows(); ++r) {
    for (std::int64_t slot = a.row_start()[r]; slot < a.row_start()[r + 1]; ++slot) {
      for (int i = 0; i < 3; ++i) {
        for (int q = 0; q < 3; ++q) {
          single(3 * r + i, 3 * a.columns()[slot] + q) =
              a.single_block(slot)[BlockSparseMatrix::kSingleColumnStride * q + i];
        }
      }
    }
  }
  detail::assemble_system(s.model, s.state, 1.1, 2e-6, detail::AssemblyTarget::kDouble);
  const Eigen::MatrixXd exact = a.to_dense();
  EXPECT_LT((single - exact).norm(), 1e-6 * exact.norm());
  std::size_t partly_held = 0;
  for (const std::int32_t d : s.model.fixed_dofs) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const double expected = j == d ? 1.0 : 0.0;
      ASSERT_EQ(single(d, j), expected) << "dof " << d << " column " << j;
      ASSERT_EQ(single(j, d), expected) << "dof " << d << " row " << j;
    }
    if (!s.model.fixed_dof_mask[static_cast<std::size_t>(d - d % 3)]) ++partly_held;
  }
  EXPECT_GT(partly_held, 0u) << "some nodes must be held on z only";
}

TEST(CoarseCorrection, AggregatesCoverEveryNodeAndEachHoldsEnoughForItsRigidMotions) {
  mesh::Mesh tet;
  tet.nodes = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.01, 0), Vec3(0, 0, 0.01)};
  tet.tets = {{0, 1, 2, 3}};
  for (const mesh::Mesh& body : {*mesh::generate_liver(mesh::LiverResolution::kSimple),
                                 *mesh::generate_liver(mesh::LiverResolution::kMedium), tet}) {
    ModelConfig c = physiological_liver_config(body);
    c.linear.coarse_correction = true;
    const Solver s = make_solver(c);
    const detail::CoarseSpace& coarse = s.state.work->coarse;
    const std::size_t n = body.nodes.size();
    ASSERT_GE(coarse.aggregates, 1) << n << " nodes";
    EXPECT_LE(coarse.aggregates, 40) << n << " nodes";
    std::vector<int> members(static_cast<std::size_t>(coarse.aggregates), 0);
    ASSERT_EQ(coarse.aggregate.size(), n);
    for (std::int32_t a : coarse.aggregate) {
      ASSERT_TRUE(a >= 0 && a < coarse.aggregates);
      ++members[static_cast<std::size_t>(a)];
    }
    for (int m : members) EXPECT_GE(m, std::min<int>(8, static_cast<int>(n))) << n << " nodes";
    EXPECT_EQ(coarse.solution.size(), 6 * coarse.aggregates);
  }
}

// The preconditioner is symmetric positive definite, so CG converges to the exact solve: in
// double precision, step after step of a press, from a coarse matrix formed once at rest
// (never refreshed) while the liver is pressed out of that shape.
TEST(CoarseCorrection, TwoLevelCgConvergesToTheExactSolveEvenWithAStaleCoarseMatrix) {
  static const mesh::Mesh simple = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  ModelConfig base = physiological_liver_config(simple);
  base.linear.mixed_precision = false;
  base.linear.iterations = 2000;
  base.linear.tolerance = 1e-24;
  base.linear.threshold = 1e-30;
  base.linear.coarse_correction = true;
  base.linear.coarse_refresh_steps = 100000;
  ModelConfig exact_config = base;
  exact_config.linear.kind = LinearSolverKind::kSparseLdlt;
  Solver exact = make_solver(exact_config);
  Solver two_level = make_solver(base);
  for (int n = 0; n < 40; ++n) {
    press(simple, exact.state, 3.0);
    press(simple, two_level.state, 3.0);
    const Eigen::VectorXd v0 = exact.state.v;
    ASSERT_TRUE(step(exact.model, exact.state));
    ASSERT_TRUE(step(two_level.model, two_level.state));
    ASSERT_TRUE(two_level.state.work->coarse.usable);
    EXPECT_EQ(two_level.state.work->coarse.built_step, 0);
    EXPECT_LT(step_error(v0, two_level.state.v, exact.state.v), 1e-6) << "step " << n;
    two_level.state.x = exact.state.x;
    two_level.state.v = exact.state.v;
  }
  EXPECT_GT((exact.state.x - Eigen::Map<const Eigen::VectorXd>(simple.nodes[0].data(), exact.state.x.size()))
                .cwiseAbs()
                .maxCoeff(),
            1e-3)
      << "the press moved the liver";
}

// What it is for: with the same few iterations from zero, the two-level CG solves a step of a
// pressed liver far better than CG with the block-Jacobi preconditioner (which leaves the
// smooth, long-wavelength part of the error).
TEST(CoarseCorrection, FourTwoLevelIterationsSolveAPressedStepFarBetterThanFourJacobiOnes) {
  static const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kCoarse);
  ModelConfig exact_config = physiological_liver_config(liver);
  exact_config.linear.kind = LinearSolverKind::kSparseLdlt;
  Solver exact = make_solver(exact_config);
  for (int n = 0; n < 30; ++n) {
    press(liver, exact.state, 2.0);
    ASSERT_TRUE(step(exact.model, exact.state));
  }
  ModelConfig jacobi_config = physiological_liver_config(liver);
  jacobi_config.linear.iterations = 4;
  jacobi_config.linear.tolerance = jacobi_config.linear.threshold = 1e-30;
  jacobi_config.linear.block_jacobi = true;
  ModelConfig two_level_config = jacobi_config;
  two_level_config.linear.block_jacobi = false;
  two_level_config.linear.coarse_correction = true;
  Solver jacobi = make_solver(jacobi_config);
  Solver two_level = make_solver(two_level_config);
  const Eigen::VectorXd x0 = exact.state.x, v0 = exact.state.v;
  for (Solver* s : {&jacobi, &two_level}) {
    s->state.x = x0;
    s->state.v = v0;
    s->state.external_force = exact.state.external_force;
    ASSERT_TRUE(step(s->model, s->state));
    EXPECT_EQ(s->state.stats.linear_iterations, 4);
  }
  ASSERT_TRUE(step(exact.model, exact.state));
  const double jacobi_error = step_error(v0, jacobi.state.v, exact.state.v);
  const double two_level_error = step_error(v0, two_level.state.v, exact.state.v);
  std::printf("%zu nodes, 4 iterations from zero: block Jacobi %.3e, two-level %.3e\n", liver.nodes.size(),
              jacobi_error, two_level_error);
  EXPECT_GT(jacobi_error, 0.1);  // the step is not trivial for CG
  EXPECT_LT(two_level_error, 0.25 * jacobi_error);
}

// A tetrahedron with three held corners (one free node: one aggregate whose rotations no node
// carries) and one held entirely: the coarse space copes and the steps stay finite.
TEST(CoarseCorrection, HeldAndTinyBodiesStillStep) {
  mesh::Mesh tet;
  tet.nodes = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.01, 0), Vec3(0, 0, 0.01)};
  tet.tets = {{0, 1, 2, 3}};
  for (const std::vector<std::int32_t>& held :
       {std::vector<std::int32_t>{0, 1, 2}, std::vector<std::int32_t>{0, 1, 2, 3}}) {
    ModelConfig c = physiological_liver_config(tet);
    c.fixed.front().indices = held;
    c.linear.coarse_correction = true;
    c.linear.iterations = 3;
    Solver s = make_solver(c);
    for (int n = 0; n < 20; ++n) ASSERT_TRUE(step(s.model, s.state)) << s.state.divergence.reason;
    EXPECT_TRUE(s.state.x.allFinite() && s.state.v.allFinite());
    if (held.size() == 4)
      EXPECT_EQ(s.state.v.cwiseAbs().maxCoeff(), 0.0);
    else
      EXPECT_LT(s.state.x[3 * 3 + 2], 0.01);  // the free corner sags under gravity
  }
}

// Parameters like any other: named, range-checked, unchanged on a refusal.
TEST(CoarseCorrection, TheTwoLevelPreconditionerAndItsRefreshAreParameters) {
  ModelConfig c = physiological_liver_config(*mesh::generate_liver(mesh::LiverResolution::kSimple));
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kCoarseCorrection}, 1.0));
  ASSERT_TRUE(
      set_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kCoarseRefreshSteps}, 50.0));
  EXPECT_TRUE(c.linear.coarse_correction);
  EXPECT_EQ(c.linear.coarse_refresh_steps, 50);
  EXPECT_EQ(*get_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kCoarseCorrection}), 1.0);
  EXPECT_EQ(*get_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kCoarseRefreshSteps}), 50.0);
  for (const auto& [id, value] :
       {std::pair{ParameterId::kCoarseCorrection, 0.5}, std::pair{ParameterId::kCoarseCorrection, 2.0},
        std::pair{ParameterId::kCoarseRefreshSteps, 0.0}, std::pair{ParameterId::kCoarseRefreshSteps, 1.5}}) {
    const std::string_view parameter = parameter_name(id);
    auto refused = set_parameter(c, ParameterRef{{ComponentKind::kLinearSolver, 0}, id}, value);
    ASSERT_FALSE(refused) << parameter << " = " << value;
    EXPECT_NE(refused.error().message.find(parameter), std::string::npos) << refused.error().message;
    EXPECT_TRUE(c.linear.coarse_correction);
    EXPECT_EQ(c.linear.coarse_refresh_steps, 50);
  }
  const auto refs = parameter_refs(c);
  EXPECT_NE(std::ranges::find(refs, ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kCoarseCorrection}),
            refs.end());
}

}  // namespace
}  // namespace hof::mechanics
