#include "hof/mechanics/step.h"

#include <fmt/format.h>

#include <cmath>

#include "hof/mechanics/linear_system.h"
#include "hof/mechanics/ode_solvers.h"
#include "hof/mechanics/parallel.h"

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

void compute_forces(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& x,
                    const Eigen::VectorXd& v, Eigen::VectorXd& f) {
  // Gravity and the coupling input first, then each force field adds its share.
  const Vec3 g = model.gravity_m_per_s2;
  const std::size_t n = model.node_count();
  parallel_chunks(n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
      f.segment<3>(k) = model.node_mass_kg[i] * g + state.external_force.segment<3>(k);
    }
  });
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    model.force_fields[k]->add_force(x, v, state.field_states[k], f);
  }
  detail::project(model, f);
}

bool compute_point_compliance(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                              std::span<const double> weights, Mat3& compliance, int max_iterations) {
  if (model.fixed_dofs.empty() || nodes.size() != weights.size() || !model.needs_matrix) return false;
  SolverWorkspace& w = state.work;
  // Linearise at the current state (refreshes element rotations), K alone, fixed dofs held.
  compute_forces(model, state, state.x, state.v, w.xt);
  detail::assemble_system(model, state, 0.0, 1.0, detail::AssemblyTarget::kDouble);
  const BlockSparseMatrix& k = w.system;
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    w.block_jacobi[n] = k.block(k.diagonal_slot(static_cast<std::int32_t>(n))).inverse();
  }
  for (int axis = 0; axis < 3; ++axis) {
    // Right-hand side Hᵀ e_axis: the unit force at the point, spread by its weights.
    w.b.setZero();
    for (std::size_t i = 0; i < nodes.size(); ++i) w.b[3 * static_cast<Eigen::Index>(nodes[i]) + axis] += weights[i];
    detail::project(model, w.b);
    const double b_norm = w.b.norm();
    if (!(b_norm > 0.0)) {
      compliance.col(axis).setZero();
      continue;
    }
    // Preconditioned CG on K y = b (K is symmetric positive definite with the fixed dofs held).
    w.dv.setZero();
    w.r = w.b;
    auto precondition = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
      for (std::size_t n = 0; n < model.node_count(); ++n) {
        const Eigen::Index i = 3 * static_cast<Eigen::Index>(n);
        out.segment<3>(i).noalias() = w.block_jacobi[n] * in.segment<3>(i);
      }
    };
    precondition(w.r, w.z);
    w.p = w.z;
    double rho = w.r.dot(w.z);
    bool converged = false;
    for (int it = 0; it < max_iterations; ++it) {
      k.multiply(w.p, w.ap);
      const double curvature = w.p.dot(w.ap);
      if (!(curvature > 0.0)) break;
      const double alpha = rho / curvature;
      w.dv += alpha * w.p;
      w.r -= alpha * w.ap;
      if (w.r.norm() <= 1e-10 * b_norm) {
        converged = true;
        break;
      }
      precondition(w.r, w.z);
      const double rho_next = w.r.dot(w.z);
      w.p = w.z + (rho_next / rho) * w.p;
      rho = rho_next;
    }
    if (!converged || !w.dv.allFinite()) return false;
    Vec3 column = Vec3::Zero();
    for (std::size_t i = 0; i < nodes.size(); ++i) column += weights[i] * w.dv.segment<3>(3 * static_cast<Eigen::Index>(nodes[i]));
    compliance.col(axis) = column;
  }
  // The true compliance is symmetric; remove the solver's round-off asymmetry.
  compliance = 0.5 * (compliance + compliance.transpose()).eval();
  return compliance.allFinite();
}

Vec3 point_elastic_force(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                         std::span<const double> weights) {
  Eigen::VectorXd& f = state.work.k1x;
  f.setZero();
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    model.force_fields[k]->add_force(state.x, state.v, state.field_states[k], f);
  }
  Vec3 total = Vec3::Zero();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    bool seen = false;  // a node listed twice counts once
    for (std::size_t j = 0; j < i; ++j) seen = seen || nodes[j] == nodes[i];
    if (!seen && weights[i] > 1e-12) total += f.segment<3>(3 * static_cast<Eigen::Index>(nodes[i]));
  }
  return total;
}

double max_residual_force(const MechanicalModel& model, MechanicalState& state) {
  compute_forces(model, state, state.x, state.v, state.f);
  double worst = 0.0;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    worst = std::max(worst, state.f.segment<3>(3 * static_cast<Eigen::Index>(i)).norm());
  }
  return worst;
}

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
