#pragma once
/// @file
/// The coarse space of the conjugate-gradient solve's two-level preconditioner.
///
/// Why: at the haptic period with SOFA's Rayleigh damping the system A = (1 + h r_M) M +
/// h (h + r_K) K is dominated by the stiffness, and CG (with or without a Jacobi
/// preconditioner) removes the smooth, long-wavelength part of the error slowly: 25 plain
/// iterations leave a third of a step of the medium liver unsolved. Those smooth errors are
/// close to rigid motions of pieces of the organ. The nodes are grouped into aggregates (a few
/// dozen, by a grid over the rest shape), each given the six rigid motions of its nodes, and
/// the preconditioner solves A exactly on that space:
///
///   M⁻¹ = D⁻¹ + P (Pᵀ A P)⁻¹ Pᵀ,
///
/// D the 3x3 diagonal blocks of A and P the rigid motions of the aggregates (a two-level
/// additive Schwarz preconditioner with smoothed-aggregation's coarse space without the
/// smoothing; Vaněk, Mandel & Brezina 1996 for rigid-body coarse spaces in elasticity; Saad,
/// Iterative Methods for Sparse Linear Systems, 2nd ed., §14.3 for the two-level method). Both
/// terms are symmetric positive definite, so CG stays CG. The coarse matrix Pᵀ A P is a small
/// dense matrix: it is formed and factored every `coarse_refresh_steps` steps from the
/// current A and positions, and reused in between; a stale coarse matrix only slows the
/// convergence, it never changes what the solve converges to.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// Groups the model's nodes into aggregates and sizes the coarse space's scratch for a CG
/// split into `chunks` chunks (allocates; once, when the state is made).
void prepare_coarse_space(const MechanicalModel& model, CoarseSpace& coarse, std::size_t chunks);

/// Forms Pᵀ A P from the solver's current matrix (the single-precision copy when the CG uses
/// it) and the state's positions, and factors it. Returns false (and leaves the space unused)
/// when the factorisation fails. Allocates nothing.
bool build_coarse_space(const MechanicalModel& model, MechanicalState& state);

/// Adds Pᵢᵀ rᵢ for the nodes [first, last) to `coarse_rhs` (6 per aggregate).
void restrict_to_coarse(const MechanicalModel& model, const CoarseSpace& coarse, const double* r, std::size_t first,
                        std::size_t last, double* coarse_rhs);

/// z += P y for the nodes [first, last), y the coarse solution (6 per aggregate).
void prolong_from_coarse(const MechanicalModel& model, const CoarseSpace& coarse, const double* y, std::size_t first,
                         std::size_t last, double* z);

}  // namespace hof::mechanics::detail
