#include "hof/app/gui/detail/component_switch.h"

#include <fmt/format.h>

#include <cmath>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::app::gui {

const std::vector<std::string> kOdeSolvers{"EulerImplicitSolver", "EulerExplicitSolver", "RungeKutta4Solver",
                                           "StaticSolver"};
const std::vector<std::string> kLinearSolvers{"CGLinearSolver", "SparseLDLSolver"};
const std::vector<std::string> kMasses{"DiagonalMass", "UniformMass"};
const std::vector<std::string> kForceFields{
    "TetrahedronFEMForceField large", "TetrahedronFEMForceField small", "TetrahedronFEMForceField polar",
    "NeoHookean (TetrahedronHyperelasticityFEMForceField)", "MeshSpringForceField"};

/// E and ν of a model's first FEM force field (SOFA's defaults otherwise).
std::pair<double, double> elastic_moduli(const mechanics::ModelConfig& c) {
  for (const mechanics::ForceFieldConfig& f : c.force_fields) {
    if (f.tetrahedron_fem) return {f.tetrahedron_fem->young_modulus_pa, f.tetrahedron_fem->poisson_ratio};
    if (f.neo_hookean) return {f.neo_hookean->young_modulus_pa, f.neo_hookean->poisson_ratio};
    if (f.hexahedron_fem) return {f.hexahedron_fem->young_modulus_pa, f.hexahedron_fem->poisson_ratio};
    if (f.triangle_fem) return {f.triangle_fem->young_modulus_pa, f.triangle_fem->poisson_ratio};
  }
  return {5000.0, 0.45};
}

double mean_edge_length(const mechanics::ModelConfig& c) {
  double sum = 0.0;
  std::size_t count = 0;
  for (const mesh::Tet& t : c.tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        sum += (c.positions[static_cast<std::size_t>(t[static_cast<std::size_t>(i)])] -
                c.positions[static_cast<std::size_t>(t[static_cast<std::size_t>(j)])])
                   .norm();
        ++count;
      }
    }
  }
  return count ? sum / static_cast<double>(count) : 0.01;
}

std::vector<std::pair<std::string, std::string>> components_of(const mechanics::ModelConfig& c) {
  std::vector<std::pair<std::string, std::string>> out;
  out.emplace_back("", "Node");
  const char* ode = c.ode.kind == mechanics::OdeSolverKind::kEulerExplicit ? "EulerExplicitSolver"
                    : c.ode.kind == mechanics::OdeSolverKind::kRungeKutta4 ? "RungeKutta4Solver"
                    : c.ode.kind == mechanics::OdeSolverKind::kStatic      ? "StaticSolver"
                                                                           : "EulerImplicitSolver";
  out.emplace_back(c.ode.name, ode);
  out.emplace_back(c.linear.name,
                   c.linear.kind == mechanics::LinearSolverKind::kSparseLdlt ? "SparseLDLSolver" : "CGLinearSolver");
  out.emplace_back(c.mass.name, c.mass.kind == mechanics::MassKind::kUniform ? "UniformMass" : "DiagonalMass");
  for (const mechanics::ForceFieldConfig& f : c.force_fields) {
    const char* type = f.mesh_springs      ? "MeshSpringForceField"
                       : f.tetrahedron_fem ? "TetrahedronFEMForceField"
                       : f.neo_hookean     ? "TetrahedronHyperelasticityFEMForceField (NeoHookean)"
                                           : "ConstantForceField";
    out.emplace_back(f.name, type);
  }
  for (const mechanics::FixedConstraintConfig& f : c.fixed) out.emplace_back(f.name, "FixedProjectiveConstraint");
  return out;
}

Expected<scene::SceneEdit> switch_edit(const mechanics::ModelConfig& c, const std::string& body,
                                       const std::string& component, const std::string& choice) {
  scene::SceneEdit edit;
  edit.action = scene::SceneEdit::Action::kReplace;
  edit.node = body;
  edit.component = component;
  const auto num = [](double v) { return fmt::format("{}", v); };
  const auto [young, poisson] = elastic_moduli(c);
  if (choice.starts_with("TetrahedronFEMForceField")) {
    edit.type = "TetrahedronFEMForceField";
    edit.attributes = {
        {"youngModulus", num(young)}, {"poissonRatio", num(poisson)}, {"method", choice.substr(choice.find(' ') + 1)}};
  } else if (choice.starts_with("NeoHookean")) {
    // SOFA's NeoHookean ParameterSet is (μ, k): the same small-strain E and ν.
    edit.type = "TetrahedronHyperelasticityFEMForceField";
    const double mu = young / (2.0 * (1.0 + poisson)), bulk = young / (3.0 * (1.0 - 2.0 * poisson));
    edit.attributes = {{"materialName", "NeoHookean"}, {"ParameterSet", num(mu) + " " + num(bulk)}};
  } else if (choice == "MeshSpringForceField") {
    // A starting point of the same order as the continuum (k ~ E·l per spring over the mean
    // edge l, a dimensional estimate; springs have no exact equivalent in 3D): tune it in the
    // panel. SOFA's MeshSpringForceField divides the value by each spring's rest length.
    edit.type = "MeshSpringForceField";
    const double edge = mean_edge_length(c);
    edit.attributes = {{"stiffness", num(young * edge * edge)}, {"damping", "0"}};
  } else if (choice == "EulerImplicitSolver") {
    edit.type = choice;
    const double rk = c.ode.kind == mechanics::OdeSolverKind::kEulerImplicit ? c.ode.rayleigh_stiffness : 0.1;
    const double rm = c.ode.kind == mechanics::OdeSolverKind::kEulerImplicit ? c.ode.rayleigh_mass : 0.1;
    edit.attributes = {{"rayleighStiffness", num(rk)}, {"rayleighMass", num(rm)}};
  } else if (choice == "EulerExplicitSolver") {
    edit.type = choice;
    edit.attributes = {{"symplectic", "1"}};
  } else if (choice == "RungeKutta4Solver" || choice == "StaticSolver") {
    edit.type = choice;
  } else if (choice == "CGLinearSolver") {
    edit.type = choice;
    edit.attributes = {{"iterations", num(c.linear.iterations)},
                       {"tolerance", num(c.linear.tolerance)},
                       {"threshold", num(c.linear.threshold)}};
  } else if (choice == "SparseLDLSolver") {
    edit.type = choice;
  } else if (choice == "UniformMass") {
    edit.type = choice;
    double total = 0.0;
    if (auto model = mechanics::build_model(c)) total = model->total_mass_kg();
    edit.attributes = {{"totalMass", num(total > 0.0 ? total : 1.0)}};
  } else if (choice == "DiagonalMass") {
    edit.type = choice;
    double total = 0.0, volume = 0.0;
    if (auto model = mechanics::build_model(c)) total = model->total_mass_kg();
    for (const mesh::Tet& t : c.tets) {
      const auto corners = mesh::tet_corners(c.positions, t);
      volume += std::abs(mesh::tet_signed_volume(corners[0], corners[1], corners[2], corners[3]));
    }
    edit.attributes = {{"massDensity", num(volume > 0.0 && total > 0.0 ? total / volume : 1000.0)}};
  } else {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("no component type '{}'", choice));
  }
  return edit;
}

}  // namespace hof::app::gui
