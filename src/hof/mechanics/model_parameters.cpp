#include "hof/mechanics/model_parameters.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <optional>

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

// The one table of names, in ParameterId's order.
constexpr std::array<std::string_view, kParameterCount> kNames{
    "dt",         "maxSpeed",  "gravityX",          "gravityY",           "gravityZ",
    "stiffness",  "damping",   "restLengthScale",   "youngModulus",       "poissonRatio",
    "thickness",  "restScale", "rayleighStiffness", "rayleighMass",       "matrixReuseSteps",
    "iterations", "warmStart", "coarseCorrection",  "coarseRefreshSteps", "tolerance",
    "threshold",  "totalMass", "massDensity"};
static_assert(static_cast<std::size_t>(ParameterId::kMassDensity) + 1 == kParameterCount);

constexpr double inf = std::numeric_limits<double>::infinity();

// Each component's slots; nullopt when the component has no parameter `id`.
std::optional<Slot> model_slot(ModelConfig& c, ParameterId id) {
  switch (id) {
    case ParameterId::kDt:
      return Slot{&c.dt_s, 0.0, 1.0, true, false, "s"};
    case ParameterId::kMaxSpeed:
      return Slot{&c.max_speed_m_per_s, 0.0, inf, true, false, "m/s"};
    case ParameterId::kGravityX:
      return Slot{&c.gravity_m_per_s2.x(), -inf, inf, false, false, "m/s^2"};
    case ParameterId::kGravityY:
      return Slot{&c.gravity_m_per_s2.y(), -inf, inf, false, false, "m/s^2"};
    case ParameterId::kGravityZ:
      return Slot{&c.gravity_m_per_s2.z(), -inf, inf, false, false, "m/s^2"};
    default:
      break;
  }
  return std::nullopt;
}

std::optional<Slot> force_field_slot(ForceFieldConfig& f, ParameterId id) {
  if (f.mesh_springs) {
    // Under SOFA's rule the value is divided by each spring's rest length: N per unit strain.
    const bool per_strain = f.mesh_springs->rule == SpringStiffnessRule::kDividedByRestLength;
    switch (id) {
      case ParameterId::kStiffness:
        return Slot{&f.mesh_springs->stiffness_n_per_m, 0.0, inf, false, false, per_strain ? "N" : "N/m"};
      case ParameterId::kDamping:
        return Slot{&f.mesh_springs->damping_n_s_per_m, 0.0, inf, false, false, per_strain ? "N s" : "N s/m"};
      case ParameterId::kRestLengthScale:
        return Slot{&f.mesh_springs->rest_length_scale, 0.0, 2.0, true, false, ""};
      default:
        break;
    }
  }
  if (f.tetrahedron_fem) {
    switch (id) {
      case ParameterId::kYoungModulus:
        return Slot{&f.tetrahedron_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      case ParameterId::kPoissonRatio:
        return Slot{&f.tetrahedron_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
      default:
        break;
    }
  }
  if (f.neo_hookean) {
    switch (id) {
      case ParameterId::kYoungModulus:
        return Slot{&f.neo_hookean->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      case ParameterId::kPoissonRatio:
        return Slot{&f.neo_hookean->poisson_ratio, -1.0, 0.5, true, false, "", true};
      default:
        break;
    }
  }
  if (f.hexahedron_fem) {
    switch (id) {
      case ParameterId::kYoungModulus:
        return Slot{&f.hexahedron_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      case ParameterId::kPoissonRatio:
        return Slot{&f.hexahedron_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
      default:
        break;
    }
  }
  if (f.triangle_fem) {
    switch (id) {
      case ParameterId::kYoungModulus:
        return Slot{&f.triangle_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
      case ParameterId::kPoissonRatio:
        return Slot{&f.triangle_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
      case ParameterId::kThickness:
        return Slot{&f.triangle_fem->thickness_m, 0.0, inf, true, false, "m"};
      case ParameterId::kRestScale:
        return Slot{&f.triangle_fem->rest_scale, 0.0, 2.0, true, false, ""};
      default:
        break;
    }
  }
  return std::nullopt;
}

std::optional<Slot> ode_slot(ModelConfig& c, ParameterId id, double& scratch) {
  switch (id) {
    case ParameterId::kRayleighStiffness:
      return Slot{&c.ode.rayleigh_stiffness, 0.0, inf, false, false, ""};
    case ParameterId::kRayleighMass:
      return Slot{&c.ode.rayleigh_mass, 0.0, inf, false, false, "1/s"};
    case ParameterId::kMatrixReuseSteps: {
      scratch = static_cast<double>(c.ode.matrix_reuse_steps);
      return Slot{&scratch, 1.0, 1000.0, false, true, "", false, &c.ode.matrix_reuse_steps};
    }
    default:
      break;
  }
  return std::nullopt;
}

std::optional<Slot> linear_slot(ModelConfig& c, ParameterId id, int& integer_storage, double& scratch) {
  switch (id) {
    case ParameterId::kIterations: {
      integer_storage = c.linear.iterations;
      scratch = static_cast<double>(integer_storage);
      return Slot{&scratch, 1.0, 100000.0, false, true, "", false, &c.linear.iterations};
    }
    case ParameterId::kWarmStart: {
      scratch = c.linear.warm_start ? 1.0 : 0.0;
      return Slot{&scratch, 0.0, 1.0, false, true, "", false, nullptr, &c.linear.warm_start};
    }
    case ParameterId::kCoarseCorrection: {
      scratch = c.linear.coarse_correction ? 1.0 : 0.0;
      return Slot{&scratch, 0.0, 1.0, false, true, "", false, nullptr, &c.linear.coarse_correction};
    }
    case ParameterId::kCoarseRefreshSteps: {
      scratch = static_cast<double>(c.linear.coarse_refresh_steps);
      return Slot{&scratch, 1.0, 100000.0, false, true, "", false, &c.linear.coarse_refresh_steps};
    }
    case ParameterId::kTolerance:
      return Slot{&c.linear.tolerance, 0.0, inf, false, false, ""};
    case ParameterId::kThreshold:
      return Slot{&c.linear.threshold, 0.0, inf, false, false, ""};
    default:
      break;
  }
  return std::nullopt;
}

std::optional<Slot> mass_slot(ModelConfig& c, ParameterId id) {
  switch (id) {
    case ParameterId::kTotalMass: {
      double* target = c.mass.kind == MassKind::kUniform ? &c.mass.total_mass_kg : nullptr;
      if (!target) {
        if (!c.mass.diagonal_total_mass_kg) c.mass.diagonal_total_mass_kg = 0.0;
        target = &*c.mass.diagonal_total_mass_kg;
      }
      return Slot{target, 0.0, inf, true, false, "kg"};
    }
    case ParameterId::kMassDensity:
      return Slot{&c.mass.mass_density_kg_per_m3, 0.0, inf, true, false, "kg/m^3"};
    default:
      break;
  }
  return std::nullopt;
}

// Finds the slot of `ref` in a (mutable) config; an error when the component is not there or
// has no such parameter.
Expected<Slot> find_slot(ModelConfig& c, ParameterRef ref, int& integer_storage, double& scratch) {
  std::optional<Slot> slot;
  switch (ref.component.kind) {
    case ComponentKind::kModel:
      slot = model_slot(c, ref.id);
      break;
    case ComponentKind::kForceField:
      if (ref.component.index >= c.force_fields.size()) {
        return make_error(
            ErrorCode::kInvalidArgument,
            fmt::format("no force field #{} (the model has {})", ref.component.index, c.force_fields.size()), c.name);
      }
      slot = force_field_slot(c.force_fields[ref.component.index], ref.id);
      break;
    case ComponentKind::kOdeSolver:
      slot = ode_slot(c, ref.id, scratch);
      break;
    case ComponentKind::kLinearSolver:
      slot = linear_slot(c, ref.id, integer_storage, scratch);
      break;
    case ComponentKind::kMass:
      slot = mass_slot(c, ref.id);
      break;
  }
  if (!slot) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} '{}' has no parameter '{}'", component_kind_name(ref.component.kind),
                                  component_name(c, ref.component), parameter_name(ref.id)),
                      c.name);
  }
  return *slot;
}

}  // namespace

std::string_view component_kind_name(ComponentKind kind) {
  switch (kind) {
    case ComponentKind::kModel:
      return "model";
    case ComponentKind::kForceField:
      return "force field";
    case ComponentKind::kOdeSolver:
      return "ODE solver";
    case ComponentKind::kLinearSolver:
      return "linear solver";
    case ComponentKind::kMass:
      return "mass";
  }
  return "component";
}

std::string_view parameter_name(ParameterId id) {
  const auto i = static_cast<std::size_t>(id);
  return i < kNames.size() ? kNames[i] : std::string_view("?");
}

std::string_view component_name(const ModelConfig& config, ComponentRef component) {
  switch (component.kind) {
    case ComponentKind::kModel:
      return {};
    case ComponentKind::kForceField:
      return component.index < config.force_fields.size() ? std::string_view(config.force_fields[component.index].name)
                                                          : std::string_view("?");
    case ComponentKind::kOdeSolver:
      return config.ode.name;
    case ComponentKind::kLinearSolver:
      return config.linear.name;
    case ComponentKind::kMass:
      return config.mass.name;
  }
  return "?";
}

Expected<void> set_parameter(ModelConfig& config, ParameterRef parameter, double value) {
  ModelConfig trial = config;  // untouched on any error (a totalMass may add an optional)
  int integer_storage = 0;
  double scratch = 0.0;
  auto slot = find_slot(trial, parameter, integer_storage, scratch);
  if (!slot) return std::unexpected(slot.error());
  const std::string_view component = component_name(config, parameter.component);
  const std::string name = component.empty() ? std::string(parameter_name(parameter.id))
                                             : fmt::format("{}/{}", component, parameter_name(parameter.id));
  const bool below = slot->lo_open ? !(value > slot->lo) : !(value >= slot->lo);
  const bool above = slot->hi_open ? !(value < slot->hi) : !(value <= slot->hi);
  if (!std::isfinite(value) || below || above || (slot->integer && value != std::floor(value))) {
    const bool unbounded = slot->hi == std::numeric_limits<double>::infinity();
    const std::string lower = slot->lo == -std::numeric_limits<double>::infinity()
                                  ? std::string("finite")
                                  : fmt::format("{} {}", slot->lo_open ? ">" : ">=", slot->lo);
    const std::string upper =
        unbounded ? std::string() : fmt::format(" and {} {}", slot->hi_open ? "<" : "<=", slot->hi);
    return make_error(
        ErrorCode::kInvalidArgument,
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

Expected<double> get_parameter(const ModelConfig& config, ParameterRef parameter) {
  ModelConfig copy = config;
  int integer_storage = 0;
  double scratch = 0.0;
  auto slot = find_slot(copy, parameter, integer_storage, scratch);
  if (!slot) return std::unexpected(slot.error());
  return *slot->value;
}

std::vector<ParameterRef> parameter_refs(const ModelConfig& c) {
  using enum ParameterId;
  std::vector<ParameterRef> refs;
  const auto add = [&](ComponentRef component, std::initializer_list<ParameterId> ids) {
    for (ParameterId id : ids) refs.push_back(ParameterRef{component, id});
  };
  add({ComponentKind::kModel, 0}, {kDt, kMaxSpeed, kGravityX, kGravityY, kGravityZ});
  for (std::uint32_t i = 0; i < c.force_fields.size(); ++i) {
    const ForceFieldConfig& f = c.force_fields[i];
    const ComponentRef field{ComponentKind::kForceField, i};
    if (f.mesh_springs) add(field, {kStiffness, kDamping, kRestLengthScale});
    if (f.tetrahedron_fem || f.neo_hookean || f.triangle_fem || f.hexahedron_fem)
      add(field, {kYoungModulus, kPoissonRatio});
    if (f.triangle_fem) add(field, {kThickness, kRestScale});
  }
  add({ComponentKind::kOdeSolver, 0}, {kRayleighStiffness, kRayleighMass, kMatrixReuseSteps});
  add({ComponentKind::kLinearSolver, 0},
      {kIterations, kTolerance, kThreshold, kWarmStart, kCoarseCorrection, kCoarseRefreshSteps});
  add({ComponentKind::kMass, 0}, {kTotalMass, kMassDensity});
  return refs;
}

}  // namespace hof::mechanics
