#pragma once
/// @file
/// Advancing a mechanical model. The stages of a step run one way, each in its own file and
/// none calling back into an earlier one:
///   step.cpp          the dispatcher: the model's integrator, then the divergence checks
///   integrators.cpp   explicit Euler, RK4, static (Newton), implicit Euler: each sequences
///   forces.cpp          1. the forces (and the element data the assembly reads)
///   assembly.cpp        2. A = αM + βK (implicit and static)
///   linear_solve.cpp    3. A·x = b by CG or LDLᵀ (implicit and static)
///                     and then integrates (updates v and x) itself.
/// Also the energies used by tests and reports. forces.h and point_compliance.h are included
/// for the callers that read forces or compliances between steps.

#include "hof/mechanics/forces.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"
#include "hof/mechanics/point_compliance.h"

namespace hof::mechanics {

/// Advances `state` by one time step of model.dt_s. Returns false when the model has diverged
/// (now or before); the state then holds the last good positions and velocities and
/// state.divergence says what happened. Never allocates after make_state().
bool step(const MechanicalModel& model, MechanicalState& state);

/// Kinetic energy ½ Σ m_i |v_i|², J.
[[nodiscard]] double kinetic_energy(const MechanicalModel& model, const MechanicalState& state);
/// Elastic energy of all force fields plus gravitational potential −Σ m_i g·x_i, J.
[[nodiscard]] double potential_energy(const MechanicalModel& model, const MechanicalState& state);

}  // namespace hof::mechanics
