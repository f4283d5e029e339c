#include "hof/mechanics/step.h"

#include <fmt/format.h>

#include <cmath>

#include "hof/mechanics/integrators.h"

namespace hof::mechanics {

namespace {

const char* solver_type(OdeSolverKind kind) {
  switch (kind) {
    case OdeSolverKind::kEulerExplicit: return "EulerExplicitSolver";
    case OdeSolverKind::kRungeKutta4: return "RungeKutta4Solver";
    case OdeSolverKind::kStatic: return "StaticSolver";
    case OdeSolverKind::kEulerImplicit: return "EulerImplicitSolver";
  }
  return "solver";
}

void diverge(MechanicalState& state, std::string component, std::string reason) {
  state.divergence.diverged = true;
  state.divergence.step = state.steps;
  state.divergence.component = std::move(component);
  state.divergence.reason = std::move(reason);
}

// First node whose position or velocity is not finite or whose speed exceeds the limit, as
// (node, is_speed). Deterministic scan.
std::pair<std::int64_t, bool> find_bad_node(const MechanicalModel& model, const MechanicalState& state) {
  const double max_speed2 = model.max_speed_m_per_s * model.max_speed_m_per_s;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
    const auto xi = state.x.segment<3>(k);
    const auto vi = state.v.segment<3>(k);
    if (!xi.allFinite() || !vi.allFinite()) return {static_cast<std::int64_t>(i), false};
    if (vi.squaredNorm() > max_speed2) return {static_cast<std::int64_t>(i), true};
  }
  return {-1, false};
}

}  // namespace

bool step(const MechanicalModel& model, MechanicalState& state) {
  if (state.divergence.diverged) return false;
  SolverWorkspace& w = state.work;
  w.x_saved = state.x;
  w.v_saved = state.v;
  state.stats = {};

  bool ok = true;
  state.arena->execute([&] {
    switch (model.ode.kind) {
      case OdeSolverKind::kEulerExplicit: ok = detail::explicit_euler_step(model, state); break;
      case OdeSolverKind::kRungeKutta4: ok = detail::runge_kutta4_step(model, state); break;
      case OdeSolverKind::kStatic: ok = detail::static_step(model, state); break;
      case OdeSolverKind::kEulerImplicit: ok = detail::implicit_euler_step(model, state); break;
    }
  });

  // Divergence: a broken solve, a non-finite or runaway node, a linear element turned inside
  // out. The state goes back to the last good step; nothing non-finite leaves this function.
  if (!ok) {
    const char* type = model.linear.kind == LinearSolverKind::kSparseLdlt ? "SparseLDLSolver" : "CGLinearSolver";
    diverge(state, fmt::format("{} '{}'", type, model.linear.name),
            "the linear solve broke down (singular or non-finite system)");
  } else {
    const auto [node, speed] = find_bad_node(model, state);
    // Names are formatted only on failure: a good step allocates nothing.
    auto solver = [&] { return fmt::format("{} '{}'", solver_type(model.ode.kind), model.ode.name); };
    if (node >= 0 && !speed) {
      diverge(state, solver(), fmt::format("node {} has a non-finite position or velocity", node));
    }
    // An inverted linear element explains a runaway better than the speed does: look first.
    for (const auto& field : model.force_fields) {
      if (state.divergence.diverged) break;
      if (const std::int64_t element = field->find_invalid_element(state.x); element >= 0) {
        diverge(state, fmt::format("{} '{}'", field->type_name(), field->name()),
                fmt::format("{} {} is inverted: linear (small) FEM cannot recover; use method "
                            "\"large\" or \"polar\", or a Neo-Hookean material",
                            field->type_name() == "HexahedronFEMForceField" ? "hexahedron" : field->type_name() == "TetrahedronFEMForceField" ? "tetrahedron" : "element", element));
      }
    }
    if (!state.divergence.diverged && node >= 0 && speed) {
      diverge(state, solver(),
              fmt::format("node {} moves at {:.3g} m/s, above the {:.3g} m/s limit: the simulation is "
                          "unstable (reduce dt, raise damping or use an implicit solver)",
                          node, state.velocity(static_cast<std::int32_t>(node)).norm(), model.max_speed_m_per_s));
    }
  }
  if (state.divergence.diverged) {
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
