#include "hof/mechanics/model_parameters.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <limits>

namespace hof::mechanics {

namespace {

// One named parameter: where it lives and its range [lo, hi] (inclusive unless open).
struct Slot {
  double* value{nullptr};
  double lo{0.0}, hi{0.0};
  bool lo_open{false};
  bool integer{false};
  const char* unit{""};
  bool hi_open{false};
  int* integer_target{nullptr};  // integer parameters: where the value goes (value points at a scratch copy)
  bool* flag_target{nullptr};    // on/off parameters (0 or 1)
};

// Finds the slot of (component, parameter) in a (mutable) config; nullopt-like Slot when absent.
Expected<Slot> find_slot(ModelConfig& c, std::string_view component, std::string_view parameter, int& integer_storage,
                         double& scratch) {
  const auto inf = std::numeric_limits<double>::infinity();
  const auto no_parameter = [&](const char* kind) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} '{}' has no parameter '{}'", kind, component, parameter), c.name);
  };
  if (component.empty()) {
    if (parameter == "dt") return Slot{&c.dt_s, 0.0, 1.0, true, false, "s"};
    if (parameter == "maxSpeed") return Slot{&c.max_speed_m_per_s, 0.0, inf, true, false, "m/s"};
    if (parameter == "gravityX") return Slot{&c.gravity_m_per_s2.x(), -inf, inf, false, false, "m/s^2"};
    if (parameter == "gravityY") return Slot{&c.gravity_m_per_s2.y(), -inf, inf, false, false, "m/s^2"};
    if (parameter == "gravityZ") return Slot{&c.gravity_m_per_s2.z(), -inf, inf, false, false, "m/s^2"};
    return no_parameter("model");
  }
  for (ForceFieldConfig& f : c.force_fields) {
    if (f.name != component) continue;
    if (f.mesh_springs) {
      // Under SOFA's rule the value is divided by each spring's rest length: N per unit strain.
      const bool per_strain = f.mesh_springs->rule == SpringStiffnessRule::kDividedByRestLength;
      if (parameter == "stiffness") return Slot{&f.mesh_springs->stiffness_n_per_m, 0.0, inf, false, false, per_strain ? "N" : "N/m"};
      if (parameter == "damping") return Slot{&f.mesh_springs->damping_n_s_per_m, 0.0, inf, false, false, per_strain ? "N s" : "N s/m"};
      if (parameter == "restLengthScale") return Slot{&f.mesh_springs->rest_length_scale, 0.0, 2.0, true, false, ""};
    }
    if (f.tetrahedron_fem) {
      if (parameter == "youngModulus") return Slot{&f.tetrahedron_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      if (parameter == "poissonRatio") return Slot{&f.tetrahedron_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
    }
    if (f.neo_hookean) {
      if (parameter == "youngModulus") return Slot{&f.neo_hookean->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      if (parameter == "poissonRatio") return Slot{&f.neo_hookean->poisson_ratio, -1.0, 0.5, true, false, "", true};
    }
    if (f.hexahedron_fem) {
      if (parameter == "youngModulus") return Slot{&f.hexahedron_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      if (parameter == "poissonRatio") return Slot{&f.hexahedron_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
    }
    if (f.triangle_fem) {
      if (parameter == "youngModulus") return Slot{&f.triangle_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      if (parameter == "poissonRatio") return Slot{&f.triangle_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
      if (parameter == "thickness") return Slot{&f.triangle_fem->thickness_m, 0.0, inf, true, false, "m"};
      if (parameter == "restScale") return Slot{&f.triangle_fem->rest_scale, 0.0, 2.0, true, false, ""};
    }
    return no_parameter("force field");
  }
  if (c.ode.name == component) {
    if (parameter == "rayleighStiffness") return Slot{&c.ode.rayleigh_stiffness, 0.0, inf, false, false, ""};
    if (parameter == "rayleighMass") return Slot{&c.ode.rayleigh_mass, 0.0, inf, false, false, "1/s"};
    if (parameter == "matrixReuseSteps") {
      scratch = static_cast<double>(c.ode.matrix_reuse_steps);
      return Slot{&scratch, 1.0, 1000.0, false, true, "", false, &c.ode.matrix_reuse_steps};
    }
    return no_parameter("ODE solver");
  }
  if (c.linear.name == component) {
    if (parameter == "iterations") {
      integer_storage = c.linear.iterations;
      scratch = static_cast<double>(integer_storage);
      return Slot{&scratch, 1.0, 100000.0, false, true, "", false, &c.linear.iterations};
    }
    if (parameter == "warmStart") {
      scratch = c.linear.warm_start ? 1.0 : 0.0;
      return Slot{&scratch, 0.0, 1.0, false, true, "", false, nullptr, &c.linear.warm_start};
    }
    if (parameter == "coarseCorrection") {
      scratch = c.linear.coarse_correction ? 1.0 : 0.0;
      return Slot{&scratch, 0.0, 1.0, false, true, "", false, nullptr, &c.linear.coarse_correction};
    }
    if (parameter == "coarseRefreshSteps") {
      scratch = static_cast<double>(c.linear.coarse_refresh_steps);
      return Slot{&scratch, 1.0, 100000.0, false, true, "", false, &c.linear.coarse_refresh_steps};
    }
    if (parameter == "tolerance") return Slot{&c.linear.tolerance, 0.0, inf, false, false, ""};
    if (parameter == "threshold") return Slot{&c.linear.threshold, 0.0, inf, false, false, ""};
    return no_parameter("linear solver");
  }
  if (c.mass.name == component) {
    if (parameter == "totalMass") {
      double* target = c.mass.kind == MassKind::kUniform ? &c.mass.total_mass_kg : nullptr;
      if (!target) {
        if (!c.mass.diagonal_total_mass_kg) c.mass.diagonal_total_mass_kg = 0.0;
        target = &*c.mass.diagonal_total_mass_kg;
      }
      return Slot{target, 0.0, inf, true, false, "kg"};
    }
    if (parameter == "massDensity") return Slot{&c.mass.mass_density_kg_per_m3, 0.0, inf, true, false, "kg/m^3"};
    return no_parameter("mass");
  }
  return make_error(ErrorCode::kInvalidArgument, fmt::format("no component '{}' (parameters: {})", component,
                                                      fmt::join(parameter_names(c), ", ")),
                    c.name);
}

}  // namespace

Expected<void> set_parameter(ModelConfig& config, std::string_view component, std::string_view parameter, double value) {
  ModelConfig trial = config;  // untouched on any error (a totalMass may add an optional)
  int integer_storage = 0;
  double scratch = 0.0;
  auto slot = find_slot(trial, component, parameter, integer_storage, scratch);
  if (!slot) return std::unexpected(slot.error());
  const std::string name = component.empty() ? std::string(parameter) : fmt::format("{}/{}", component, parameter);
  const bool below = slot->lo_open ? !(value > slot->lo) : !(value >= slot->lo);
  const bool above = slot->hi_open ? !(value < slot->hi) : !(value <= slot->hi);
  if (!std::isfinite(value) || below || above ||
      (slot->integer && value != std::floor(value))) {
    const bool unbounded = slot->hi == std::numeric_limits<double>::infinity();
    const std::string lower = slot->lo == -std::numeric_limits<double>::infinity()
                                  ? std::string("finite")
                                  : fmt::format("{} {}", slot->lo_open ? ">" : ">=", slot->lo);
    const std::string upper = unbounded ? std::string() : fmt::format(" and {} {}", slot->hi_open ? "<" : "<=", slot->hi);
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} = {} is out of range: it must be {}{}{}{}", name, value, lower, upper,
                                  slot->integer ? ", an integer" : "", *slot->unit ? fmt::format(" ({})", slot->unit) : ""),
                      config.name);
  }
  *slot->value = value;
  if (slot->integer_target) *slot->integer_target = static_cast<int>(value);
  if (slot->flag_target) *slot->flag_target = value != 0.0;
  config = std::move(trial);
  return {};
}

Expected<double> get_parameter(const ModelConfig& config, std::string_view component, std::string_view parameter) {
  ModelConfig copy = config;
  int integer_storage = 0;
  double scratch = 0.0;
  auto slot = find_slot(copy, component, parameter, integer_storage, scratch);
  if (!slot) return std::unexpected(slot.error());
  return *slot->value;
}

std::vector<std::string> parameter_names(const ModelConfig& c) {
  std::vector<std::string> names{"dt", "maxSpeed", "gravityX", "gravityY", "gravityZ"};
  for (const ForceFieldConfig& f : c.force_fields) {
    if (f.mesh_springs) {
      names.push_back(f.name + "/stiffness");
      names.push_back(f.name + "/damping");
      names.push_back(f.name + "/restLengthScale");
    }
    if (f.tetrahedron_fem || f.neo_hookean || f.triangle_fem || f.hexahedron_fem) {
      names.push_back(f.name + "/youngModulus");
      names.push_back(f.name + "/poissonRatio");
    }
    if (f.triangle_fem) {
      names.push_back(f.name + "/thickness");
      names.push_back(f.name + "/restScale");
    }
  }
  names.push_back(c.ode.name + "/rayleighStiffness");
  names.push_back(c.ode.name + "/rayleighMass");
  names.push_back(c.ode.name + "/matrixReuseSteps");
  names.push_back(c.linear.name + "/iterations");
  names.push_back(c.linear.name + "/tolerance");
  names.push_back(c.linear.name + "/threshold");
  names.push_back(c.linear.name + "/warmStart");
  names.push_back(c.linear.name + "/coarseCorrection");
  names.push_back(c.linear.name + "/coarseRefreshSteps");
  names.push_back(c.mass.name + "/totalMass");
  names.push_back(c.mass.name + "/massDensity");
  // The model's own (component ""): "/dt", ...
  for (const char* own : {"dt", "maxSpeed", "gravityX", "gravityY", "gravityZ"}) names.push_back(std::string("/") + own);
  return names;
}

}  // namespace hof::mechanics
