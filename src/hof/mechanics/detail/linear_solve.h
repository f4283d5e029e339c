#pragma once
/// @file
/// Stage 3 of an implicit or static step: the solution of A·x = b (A as the assembly stage
/// left it) by conjugate gradients or a sparse direct factorisation (CHOLMOD).

#include <Eigen/Core>
#include <cstdint>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// Whether the CG product uses the single-precision copy of A (which the assembly then fills).
inline bool uses_single_precision(const MechanicalModel& model) {
  return model.linear.kind == LinearSolverKind::kConjugateGradient && model.linear.mixed_precision;
}

/// Solves A·x = b with the model's linear solver (x starts from zero, or from the last
/// solution with a warm start). b's fixed entries must be zero. Fills
/// state.stats.linear_iterations and linear_residual. Returns false when the solve broke down
/// (non-finite values, a failed factorisation).
bool solve_system(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x);

/// Sets up the solver scratch that depends on the pattern (CSC map, the direct solver's
/// fill-reducing ordering and symbolic analysis, the CG's exchange between `threads` threads).
void prepare_linear_solver(const MechanicalModel& model, MechanicalState& state, int threads);

/// The fill-reducing ordering the direct solver chose (AMD and METIS are both tried, the one
/// with the sparser factor kept).
enum class DirectOrdering : std::uint8_t { kNone, kAmd, kMetis, kNestedDissection, kOther };

/// What the sparse direct solver of a state factors with (tests, benchmarks, reports).
struct DirectSolverInfo {
  bool prepared{false};            ///< the state has a direct solver (kSparseLdlt and a matrix)
  bool supernodal{false};          ///< the main factor is CHOLMOD's supernodal LLᵀ
  bool last_used_fallback{false};  ///< the last factorisation found A not positive definite: simplicial LDLᵀ solved
  std::int64_t factorisations{0};  ///< numeric factorisations so far (main and fallback)
  DirectOrdering ordering{DirectOrdering::kNone};
  double factor_nonzeros{0.0};  ///< nnz(L)
  double factor_flops{0.0};     ///< floating-point operations of one factorisation
};

/// The direct solver's figures for `state` (prepared false when it has none).
[[nodiscard]] DirectSolverInfo direct_solver_info(const MechanicalState& state);

/// Re-plans the CG's exchange for `threads` threads: the pattern and the matrix's values are
/// kept (a reused matrix stays valid). Between steps; it allocates.
void prepare_cg_threads(const MechanicalModel& model, MechanicalState& state, int threads);

}  // namespace hof::mechanics::detail
