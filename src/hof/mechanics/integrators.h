#pragma once
/// @file
/// The time integrators behind step() (see step.h for the stages). Each runs the stages its
/// scheme needs — forces, then for the implicit and static ones assembly and solve — and
/// integrates: advances state.x and state.v by model.dt_s. Returns false if its linear solve
/// broke down.

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// Explicit Euler; symplectic (semi-implicit) when model.ode.symplectic: v ← v + h M⁻¹f(x, v),
/// x ← x + h v_new; otherwise x ← x + h v_old.
bool explicit_euler_step(const MechanicalModel& model, MechanicalState& state);

/// Classic fourth-order Runge–Kutta on (x, v), four force evaluations per step.
bool runge_kutta4_step(const MechanicalModel& model, MechanicalState& state);

/// Implicit (backward) Euler linearised once per step (Baraff & Witkin, SIGGRAPH 1998), with
/// Rayleigh damping as in SOFA's EulerImplicitSolver:
///   [(1 + h r_M) M + h (h + r_K) K] Δv = h f − h (h + r_K) K v − h r_M M v,
///   v ← v + Δv, x ← x + h v.
bool implicit_euler_step(const MechanicalModel& model, MechanicalState& state);

/// Static equilibrium by Newton iterations on f(x) = 0: K Δx = f, x ← x + Δx, with a
/// backtracking step when the residual grows. Velocities are zero.
bool static_step(const MechanicalModel& model, MechanicalState& state);

}  // namespace hof::mechanics::detail
