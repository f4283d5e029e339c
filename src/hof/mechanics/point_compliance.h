#pragma once
/// @file
/// The body's compliance at a contact point: the local model the haptic loop renders at 1 kHz
/// between simulation steps (compliance coupling).

#include <span>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics {

/// The 3x3 compliance of the body at a point (m/N): how far the point moves per newton
/// applied there, other forces fixed, from the stiffness linearised at the current state with
/// the fixed nodes held — the local contact model the haptic loop renders at 1 kHz
/// (Saupin, Duriez & Cotin, ISBMS 2008). The point is Σ weights[k]·x[nodes[k]]. Solved by
/// block-Jacobi-preconditioned CG to 1e-10 relative residual in the state's scratch (call it
/// between steps; no allocation). Returns false when the body is not held (singular
/// stiffness) or the solve fails or needs more than `max_iterations` per axis.
bool compute_point_compliance(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                              std::span<const double> weights, Mat3& compliance, int max_iterations = 5000);

/// The node's 3x3 diagonal block of the matrix the last implicit Euler step solved,
/// A = (1 + h r_M) M + h (h + r_K) K (plus the external stiffness), kg, with the rows and
/// columns of held dofs as the projection left them. False when the state holds no such
/// matrix (another integrator, before the first step, or after compute_point_compliance
/// replaced it by K) or the node is out of range. Reads only; no allocation. The contact
/// constraints' compliance h²·A_ii⁻¹ (coupling/detail/body_contact_constraints.h).
bool system_diagonal_block(const MechanicalModel& model, const MechanicalState& state, std::int32_t node, Mat3& block);

}  // namespace hof::mechanics
