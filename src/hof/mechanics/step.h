#pragma once
/// @file
/// Advancing a mechanical model. step() (step.cpp) runs the stages of a step itself, one way,
/// none calling back into an earlier one:
///   1. forces.cpp                the forces at x, v (and the element data the assembly reads)
///   2. detail/<integrator>.cpp   one leaf file per scheme — explicit_euler, runge_kutta4,
///                                implicit_euler, static_solver — which assembles A = αM + βK
///                                (detail/assembly.cpp) and solves A·x = b by CG or LDLᵀ
///                                (detail/linear_solve.cpp) when it needs to, then updates v and x
///   3. the divergence checks, which record a Fault (fault.h) and put it in words
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
