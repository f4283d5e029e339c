// The sparse direct solver (kSparseLdlt, issue 35): CHOLMOD's supernodal factorisation on a
// fill-reducing ordering, analysed once; its solution equals an independent factorisation of
// the same matrix (Eigen's simplicial LDLᵀ) to 1e-10; a matrix that is not positive definite
// falls back to LDLᵀ. Speed is the benchmark's (Liver/*/FEMLarge/ImplicitLDLT), never asserted.

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cstdio>
#include <random>
#include <vector>

#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/liver_generator.h"

#include "physiological_liver.h"

namespace hof::mechanics {
namespace {

// The benchmark's implicit liver (co-rotational FEM, E 30 kPa, ν 0.45, Rayleigh 0.1/0.1,
// dt 0.02 s) held by three nodes of its top, with the direct solver: the physiological liver
// of the other solver tests with the benchmark's modulus, supports and step.
ModelConfig liver_config(mesh::LiverResolution resolution) {
  ModelConfig c = testing::physiological_liver_config(*mesh::generate_liver(resolution));
  c.force_fields.front().tetrahedron_fem->young_modulus_pa = 30000.0;
  c.fixed = {FixedConstraintConfig{"fixed", {0, 1, 2}, std::nullopt, false, {true, true, true}}};
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  c.dt_s = 0.02;
  return c;
}

// The block matrix as an Eigen sparse matrix (both triangles).
Eigen::SparseMatrix<double> to_sparse(const BlockSparseMatrix& a) {
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::int32_t r = 0; r < a.block_rows(); ++r) {
    for (std::int64_t s = a.row_start()[r]; s < a.row_start()[r + 1]; ++s) {
      const std::int32_t c = a.columns()[s];
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) triplets.emplace_back(3 * r + i, 3 * c + j, a.block(s)(i, j));
      }
    }
  }
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(a.block_rows());
  Eigen::SparseMatrix<double> m(n, n);
  m.setFromTriplets(triplets.begin(), triplets.end());
  return m;
}

// A right-hand side with the fixed entries zero (solve_system's precondition).
Eigen::VectorXd random_rhs(const MechanicalModel& model) {
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd b(3 * static_cast<Eigen::Index>(model.node_count()));
  for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = model.fixed_dof_mask[static_cast<std::size_t>(i)] ? 0.0 : u(rng);
  return b;
}

TEST(DirectSolver, FactorsSupernodallyOnAFillReducingOrderingAnalysedOnce) {
  auto model = build_model(liver_config(mesh::LiverResolution::kCoarse));
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  const detail::DirectSolverInfo before = detail::direct_solver_info(state);
  ASSERT_TRUE(before.prepared);
  EXPECT_TRUE(before.supernodal);
  EXPECT_TRUE(before.ordering == detail::DirectOrdering::kAmd || before.ordering == detail::DirectOrdering::kMetis ||
              before.ordering == detail::DirectOrdering::kNestedDissection);
  EXPECT_EQ(before.factorisations, 0);
  // Fill-reducing: far below the dense lower triangle's n²/2.
  const double n = 3.0 * static_cast<double>(model->node_count());
  EXPECT_GT(before.factor_nonzeros, n);
  EXPECT_LT(before.factor_nonzeros, 0.2 * n * n / 2);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
  const detail::DirectSolverInfo after = detail::direct_solver_info(state);
  EXPECT_EQ(after.factorisations, 3);  // one numeric factorisation per step, the analysis kept
  EXPECT_FALSE(after.last_used_fallback);
  EXPECT_EQ(after.factor_nonzeros, before.factor_nonzeros);
  // CG and models without a matrix have none.
  ModelConfig cg = liver_config(mesh::LiverResolution::kSimple);
  cg.linear.kind = LinearSolverKind::kConjugateGradient;
  auto cg_model = build_model(cg);
  ASSERT_TRUE(cg_model) << cg_model.error().to_string();
  EXPECT_FALSE(detail::direct_solver_info(make_state(*cg_model)).prepared);
}

// The medium liver's implicit system after a few steps (rotated elements), solved by the step's
// solver and by Eigen's simplicial LDLᵀ on its own AMD ordering: the same answer to 1e-10.
TEST(DirectSolver, SolutionEqualsAnIndependentFactorisation) {
  auto model = build_model(liver_config(mesh::LiverResolution::kMedium));
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
  const Eigen::SparseMatrix<double> a = to_sparse(state.work->system);
  const Eigen::VectorXd b = random_rhs(*model);
  Eigen::VectorXd x(b.size());
  ASSERT_TRUE(detail::solve_system(*model, state, b, x));
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> reference(a);
  ASSERT_EQ(reference.info(), Eigen::Success);
  const Eigen::VectorXd x_reference = reference.solve(b);
  const double difference = (x - x_reference).norm() / x_reference.norm();
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", difference);
  RecordProperty("relative_difference", text);
  EXPECT_LT(difference, 1e-10);
  EXPECT_LT((a * x - b).norm() / b.norm(), 1e-12);
  // The step's own solve: its velocity change solves the step's system.
  EXPECT_LT((a * state.work->dv - state.work->b).norm() / state.work->b.norm(), 1e-12);
}

// A matrix that is not positive definite (here one free node's diagonal block negated, which
// keeps it symmetric and non-singular): LLᵀ stops, simplicial LDLᵀ solves it.
TEST(DirectSolver, FallsBackToLdltWhenNotPositiveDefinite) {
  auto model = build_model(liver_config(mesh::LiverResolution::kSimple));
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
  BlockSparseMatrix& system = state.work->system;
  const std::int32_t node = 10;
  ASSERT_FALSE(model->fixed_dof_mask[3 * node]);
  system.block(system.diagonal_slot(node)) *= -1.0;
  const Eigen::SparseMatrix<double> a = to_sparse(system);
  const Eigen::VectorXd b = random_rhs(*model);
  Eigen::VectorXd x(b.size());
  ASSERT_TRUE(detail::solve_system(*model, state, b, x));
  EXPECT_TRUE(detail::direct_solver_info(state).last_used_fallback);
  EXPECT_LT((a * x - b).norm() / b.norm(), 1e-10);
  // The next positive definite matrix is factored supernodally again.
  ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
  EXPECT_FALSE(detail::direct_solver_info(state).last_used_fallback);
}

}  // namespace
}  // namespace hof::mechanics
