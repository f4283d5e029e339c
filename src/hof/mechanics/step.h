#pragma once
/// @file
/// Advancing a mechanical model: step() reads like the algorithm — forces (internal, gravity,
/// constant, coupling input) → solve (the model's ODE solver) → project constraints → check
/// for divergence. Also the energies used by tests and reports.

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

#include <span>

namespace hof::mechanics {

/// Advances `state` by one time step of model.dt_s. Returns false when the model has diverged
/// (now or before); the state then holds the last good positions and velocities and
/// state.divergence says what happened. Never allocates after make_state().
bool step(const MechanicalModel& model, MechanicalState& state);

/// Kinetic energy ½ Σ m_i |v_i|², J.
[[nodiscard]] double kinetic_energy(const MechanicalModel& model, const MechanicalState& state);
/// Elastic energy of all force fields plus gravitational potential −Σ m_i g·x_i, J.
[[nodiscard]] double potential_energy(const MechanicalModel& model, const MechanicalState& state);

/// Total force at the state's positions and velocities (internal + gravity + constant +
/// external), with fixed nodes' entries set to zero. Also refreshes per-field element data.
void compute_forces(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& x,
                    const Eigen::VectorXd& v, Eigen::VectorXd& f);

/// The 3x3 compliance of the body at a point (m/N): how far the point moves per newton
/// applied there, other forces fixed, from the stiffness linearised at the current state with
/// the fixed nodes held — the local contact model the haptic loop renders at 1 kHz
/// (Saupin, Duriez & Cotin, ISBMS 2008). The point is Σ weights[k]·x[nodes[k]]. Solved by
/// block-Jacobi-preconditioned CG to 1e-10 relative residual in the state's scratch (call it
/// between steps; no allocation). Returns false when the body is not held (singular
/// stiffness) or the solve fails or needs more than `max_iterations` per axis.
bool compute_point_compliance(const MechanicalModel& model, MechanicalState& state,
                              std::span<const std::int32_t> nodes, std::span<const double> weights, Mat3& compliance,
                              int max_iterations = 5000);

/// The elastic force the body exerts at a point (N): the force fields' forces (no gravity, no
/// external input) summed over the nodes that carry the point (`weights` > 0). For a body
/// held still by a load at that point, it is minus that load. Scratch only; no allocation.
Vec3 point_elastic_force(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                         std::span<const double> weights);

/// Largest residual force on a free node (N): how far from static equilibrium the state is.
[[nodiscard]] double max_residual_force(const MechanicalModel& model, MechanicalState& state);

}  // namespace hof::mechanics
