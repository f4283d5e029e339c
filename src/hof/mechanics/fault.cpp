#include "hof/mechanics/fault.h"

#include <fmt/format.h>

#include "hof/mechanics/mechanical_model.h"

namespace hof::mechanics {

namespace {

const char* solver_type(OdeSolverKind kind) {
  switch (kind) {
    case OdeSolverKind::kEulerExplicit:
      return "EulerExplicitSolver";
    case OdeSolverKind::kRungeKutta4:
      return "RungeKutta4Solver";
    case OdeSolverKind::kStatic:
      return "StaticSolver";
    case OdeSolverKind::kEulerImplicit:
      return "EulerImplicitSolver";
  }
  return "solver";
}

std::string ode_solver(const MechanicalModel& model) {
  return fmt::format("{} '{}'", solver_type(model.ode.kind), model.ode.name);
}

}  // namespace

FaultText describe_fault(const MechanicalModel& model, const Fault& fault) {
  switch (fault.kind) {
    case FaultKind::kNone:
      return {};
    case FaultKind::kLinearSolveFailed: {
      const char* type = model.linear.kind == LinearSolverKind::kSparseLdlt ? "SparseLDLSolver" : "CGLinearSolver";
      return {fmt::format("{} '{}'", type, model.linear.name),
              "the linear solve broke down (singular or non-finite system)"};
    }
    case FaultKind::kNonFiniteNode:
      return {ode_solver(model), fmt::format("node {} has a non-finite position or velocity", fault.index)};
    case FaultKind::kInvertedElement: {
      const ForceField& field = *model.force_fields[static_cast<std::size_t>(fault.field)];
      return {fmt::format("{} '{}'", field.type_name(), field.name()),
              fmt::format("{} {} is inverted: linear (small) FEM cannot recover; use method "
                          "\"large\" or \"polar\", or a Neo-Hookean material",
                          field.element_noun(), fault.index)};
    }
    case FaultKind::kRunawayNode:
      return {ode_solver(model),
              fmt::format("node {} moves at {:.3g} m/s, above the {:.3g} m/s limit: the simulation is "
                          "unstable (reduce dt, raise damping or use an implicit solver)",
                          fault.index, fault.value, model.max_speed_m_per_s)};
  }
  return {};
}

}  // namespace hof::mechanics
