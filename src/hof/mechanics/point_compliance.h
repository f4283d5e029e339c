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

}  // namespace hof::mechanics
