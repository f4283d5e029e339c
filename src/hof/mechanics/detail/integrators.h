#pragma once
/// @file
/// The time integrators behind step(), one per file (explicit_euler.cpp, runge_kutta4.cpp,
/// implicit_euler.cpp, static_solver.cpp). step() has already evaluated the forces at the
/// state's positions and velocities into state.f (stage 1); each integrator runs the stages
/// its scheme still needs — assembly and solve for the implicit and static ones, further force
/// evaluations for RK4 and the static line search — and advances state.x and state.v by
/// model.dt_s. Returns false if its linear solve broke down. None calls back into step().

#include <chrono>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

using StageClock = std::chrono::steady_clock;

inline double seconds_since(StageClock::time_point start) {
  return std::chrono::duration<double>(StageClock::now() - start).count();
}

/// Explicit Euler; symplectic (semi-implicit) when model.ode.symplectic: v ← v + h M⁻¹f(x, v),
/// x ← x + h v_new; otherwise x ← x + h v_old.
bool explicit_euler_step(const MechanicalModel& model, MechanicalState& state);

/// Classic fourth-order Runge–Kutta on (x, v); its first force evaluation is step()'s, the
/// other three its own.
bool runge_kutta4_step(const MechanicalModel& model, MechanicalState& state);

/// Implicit (backward) Euler linearised once per step (Baraff & Witkin, SIGGRAPH 1998), with
/// Rayleigh damping as in SOFA's EulerImplicitSolver:
///   [(1 + h r_M) M + h (h + r_K) K] Δv = h f − h (h + r_K) K v − h r_M M v,
///   v ← v + Δv, x ← x + h v.
bool implicit_euler_step(const MechanicalModel& model, MechanicalState& state);

/// Static equilibrium by Newton iterations on f(x) = 0: K Δx = f, x ← x + Δx, with a
/// backtracking step when the residual grows. Velocities are zero (step() clears them before
/// the first force evaluation).
bool static_step(const MechanicalModel& model, MechanicalState& state);

/// out = M⁻¹ in (lumped mass), fixed degrees of freedom zero.
void apply_inverse_mass(const MechanicalModel& model, const Eigen::VectorXd& in, Eigen::VectorXd& out);

/// out = M in (lumped mass).
void apply_mass(const MechanicalModel& model, const Eigen::VectorXd& in, Eigen::VectorXd& out);

}  // namespace hof::mechanics::detail
