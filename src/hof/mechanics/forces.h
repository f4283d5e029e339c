#pragma once
/// @file
/// Stage 1 of every step: the forces on the nodes at given positions and velocities
/// (internal, gravity, constant, coupling input), which also leave in each force field's state
/// the element data (rotations, tangents) that the assembly stage reads.

#include <Eigen/Core>

#include <span>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics {

/// Total force at the state's positions and velocities (internal + gravity + constant +
/// external), with fixed nodes' entries set to zero. Also refreshes per-field element data.
void compute_forces(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& x,
                    const Eigen::VectorXd& v, Eigen::VectorXd& f);

/// The elastic force the body exerts at a point (N): the force fields' forces (no gravity, no
/// external input) summed over the nodes that carry the point (`weights` > 0). For a body
/// held still by a load at that point, it is minus that load. Evaluates only the elements that
/// touch those nodes when every force field can (ForceField::add_force_sum_on), else the whole
/// fields. Scratch in the state's workspace: it allocates only on first use or for a larger patch.
Vec3 point_elastic_force(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                         std::span<const double> weights);

/// Largest residual force on a free node (N): how far from static equilibrium the state is.
[[nodiscard]] double max_residual_force(const MechanicalModel& model, MechanicalState& state);

}  // namespace hof::mechanics
