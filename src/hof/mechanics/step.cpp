#include "hof/mechanics/step.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include "hof/mechanics/detail/integrators.h"

namespace hof::mechanics {

namespace {

// First node whose position or velocity is not finite or whose speed exceeds the limit.
// Deterministic scan.
Fault find_bad_node(const MechanicalModel& model, const MechanicalState& state) {
  const double max_speed2 = model.max_speed_m_per_s * model.max_speed_m_per_s;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
    const auto xi = state.x.segment<3>(k);
    const auto vi = state.v.segment<3>(k);
    if (!xi.allFinite() || !vi.allFinite()) return {FaultKind::kNonFiniteNode, static_cast<std::int64_t>(i), -1, 0.0};
    if (vi.squaredNorm() > max_speed2) return {FaultKind::kRunawayNode, static_cast<std::int64_t>(i), -1, vi.norm()};
  }
  return {};
}

// The divergence checks after a step, in the order that explains best: a broken solve, a
// non-finite node, a linear element turned inside out (it explains a runaway better than the
// speed does), then a runaway node.
Fault check_step(const MechanicalModel& model, const MechanicalState& state, bool solved) {
  if (!solved) return {FaultKind::kLinearSolveFailed, -1, -1, 0.0};
  const Fault node = find_bad_node(model, state);
  if (node.kind == FaultKind::kNonFiniteNode) return node;
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    if (const std::int64_t element = model.force_fields[k]->find_invalid_element(state.x); element >= 0) {
      return {FaultKind::kInvertedElement, element, static_cast<std::int32_t>(k), 0.0};
    }
  }
  return node;
}

// One step's stages, in order; the integrator is a leaf that integrates from the forces.
bool run_stages(const MechanicalModel& model, MechanicalState& state) {
  // Stage 1, the forces at the state's positions and velocities (static equilibrium: at rest).
  if (model.ode.kind == OdeSolverKind::kStatic) state.v.setZero();
  const auto t0 = detail::StageClock::now();
  compute_forces(model, state, state.x, state.v, state.f);
  state.stats.force_s = detail::seconds_since(t0);
  // Stage 2, the integrator: assembly and solve when implicit, then x and v advance.
  switch (model.ode.kind) {
    case OdeSolverKind::kEulerExplicit:
      return detail::explicit_euler_step(model, state);
    case OdeSolverKind::kRungeKutta4:
      return detail::runge_kutta4_step(model, state);
    case OdeSolverKind::kStatic:
      return detail::static_step(model, state);
    case OdeSolverKind::kEulerImplicit:
      return detail::implicit_euler_step(model, state);
  }
  return true;
}

}  // namespace

bool step(const MechanicalModel& model, MechanicalState& state) {
  if (state.divergence.diverged) return false;
  detail::SolverWorkspace& w = *state.work;
  w.x_saved = state.x;
  w.v_saved = state.v;
  state.stats = {};

  bool solved = true;
  state.work->arena->execute([&] { solved = run_stages(model, state); });

  // Divergence: the state goes back to the last good step; nothing non-finite leaves this
  // function. The fault is put in words here, at the edge, and only on failure: a good step
  // allocates nothing.
  if (const Fault fault = check_step(model, state, solved); fault.kind != FaultKind::kNone) {
    FaultText text = describe_fault(model, fault);
    state.divergence = {true, state.steps, fault, std::move(text.component), std::move(text.reason)};
    state.x = w.x_saved;
    state.v = w.v_saved;
    state.f.setZero();
    return false;
  }
  state.time_s += model.dt_s;
  ++state.steps;
  return true;
}

double kinetic_energy(const MechanicalModel& model, const MechanicalState& state) {
  double e = 0.0;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    e += 0.5 * model.node_mass_kg[i] * state.v.segment<3>(3 * static_cast<Eigen::Index>(i)).squaredNorm();
  }
  return e;
}

double potential_energy(const MechanicalModel& model, const MechanicalState& state) {
  double e = 0.0;
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    e += model.force_fields[k]->potential_energy(state.x, state.field_states[k]);
  }
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    e -= model.node_mass_kg[i] * model.gravity_m_per_s2.dot(state.x.segment<3>(3 * static_cast<Eigen::Index>(i)));
  }
  return e;
}

}  // namespace hof::mechanics
