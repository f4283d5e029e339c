#include "hof/mechanics/model_parameters.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hof/core/text.h"

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
    "dt",        "maxSpeed",         "gravityX",   "gravityY",         "gravityZ",           "stiffness",
    "damping",   "restLengthScale",  "youngModulus", "poissonRatio",   "thickness",          "restScale",
    "rayleighStiffness", "rayleighMass", "matrixReuseSteps", "iterations", "warmStart",     "coarseCorrection",
    "coarseRefreshSteps", "tolerance", "threshold",  "totalMass",        "massDensity"};
static_assert(static_cast<std::size_t>(ParameterId::kMassDensity) + 1 == kParameterCount);

// A name that is no parameter's (its slot is looked up only to say what the component has).
constexpr auto kNoId = static_cast<ParameterId>(0xff);

// Finds the slot of (component, parameter) in a (mutable) config; nullopt-like Slot when absent.
// `parameter` is the name asked for (in messages; `id` is kNoId when it names no parameter).
Expected<Slot> find_slot(ModelConfig& c, std::string_view component, ParameterId id, std::string_view parameter,
                         int& integer_storage, double& scratch) {
  const auto inf = std::numeric_limits<double>::infinity();
  const auto no_parameter = [&](const char* kind) {
    // A name that is no parameter's at all: the closest names too.
    std::string closest;
    if (auto known = parameter_id(parameter); !known) {
      const std::string& why = known.error().message;
      if (const auto at = why.find(" (closest"); at != std::string::npos) closest = why.substr(at);
    }
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} '{}' has no parameter '{}'{}", kind, component, parameter, closest), c.name);
  };
  if (component.empty()) {
    switch (id) {
      case ParameterId::kDt: return Slot{&c.dt_s, 0.0, 1.0, true, false, "s"};
      case ParameterId::kMaxSpeed: return Slot{&c.max_speed_m_per_s, 0.0, inf, true, false, "m/s"};
      case ParameterId::kGravityX: return Slot{&c.gravity_m_per_s2.x(), -inf, inf, false, false, "m/s^2"};
      case ParameterId::kGravityY: return Slot{&c.gravity_m_per_s2.y(), -inf, inf, false, false, "m/s^2"};
      case ParameterId::kGravityZ: return Slot{&c.gravity_m_per_s2.z(), -inf, inf, false, false, "m/s^2"};
      default: break;
    }
    return no_parameter("model");
  }
  for (ForceFieldConfig& f : c.force_fields) {
    if (f.name != component) continue;
    if (f.mesh_springs) {
      // Under SOFA's rule the value is divided by each spring's rest length: N per unit strain.
      const bool per_strain = f.mesh_springs->rule == SpringStiffnessRule::kDividedByRestLength;
      switch (id) {
        case ParameterId::kStiffness: return Slot{&f.mesh_springs->stiffness_n_per_m, 0.0, inf, false, false, per_strain ? "N" : "N/m"};
        case ParameterId::kDamping: return Slot{&f.mesh_springs->damping_n_s_per_m, 0.0, inf, false, false, per_strain ? "N s" : "N s/m"};
        case ParameterId::kRestLengthScale: return Slot{&f.mesh_springs->rest_length_scale, 0.0, 2.0, true, false, ""};
        default: break;
      }
    }
    if (f.tetrahedron_fem) {
      switch (id) {
        case ParameterId::kYoungModulus: return Slot{&f.tetrahedron_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
        case ParameterId::kPoissonRatio: return Slot{&f.tetrahedron_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
        default: break;
      }
    }
    if (f.neo_hookean) {
      switch (id) {
        case ParameterId::kYoungModulus: return Slot{&f.neo_hookean->young_modulus_pa, 0.0, inf, true, false, "Pa"};
        case ParameterId::kPoissonRatio: return Slot{&f.neo_hookean->poisson_ratio, -1.0, 0.5, true, false, "", true};
        default: break;
      }
    }
    if (f.hexahedron_fem) {
      switch (id) {
        case ParameterId::kYoungModulus: return Slot{&f.hexahedron_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
        case ParameterId::kPoissonRatio: return Slot{&f.hexahedron_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
        default: break;
      }
    }
    if (f.triangle_fem) {
      switch (id) {
        case ParameterId::kYoungModulus: return Slot{&f.triangle_fem->young_modulus_pa, 0.0, inf, true, false, "Pa"};
        case ParameterId::kPoissonRatio: return Slot{&f.triangle_fem->poisson_ratio, -1.0, 0.5, true, false, "", true};
        case ParameterId::kThickness: return Slot{&f.triangle_fem->thickness_m, 0.0, inf, true, false, "m"};
        case ParameterId::kRestScale: return Slot{&f.triangle_fem->rest_scale, 0.0, 2.0, true, false, ""};
        default: break;
      }
    }
    return no_parameter("force field");
  }
  if (c.ode.name == component) {
    switch (id) {
      case ParameterId::kRayleighStiffness: return Slot{&c.ode.rayleigh_stiffness, 0.0, inf, false, false, ""};
      case ParameterId::kRayleighMass: return Slot{&c.ode.rayleigh_mass, 0.0, inf, false, false, "1/s"};
      case ParameterId::kMatrixReuseSteps: {
        scratch = static_cast<double>(c.ode.matrix_reuse_steps);
        return Slot{&scratch, 1.0, 1000.0, false, true, "", false, &c.ode.matrix_reuse_steps};
      }
      default: break;
    }
    return no_parameter("ODE solver");
  }
  if (c.linear.name == component) {
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
      case ParameterId::kTolerance: return Slot{&c.linear.tolerance, 0.0, inf, false, false, ""};
      case ParameterId::kThreshold: return Slot{&c.linear.threshold, 0.0, inf, false, false, ""};
      default: break;
    }
    return no_parameter("linear solver");
  }
  if (c.mass.name == component) {
    switch (id) {
      case ParameterId::kTotalMass: {
        double* target = c.mass.kind == MassKind::kUniform ? &c.mass.total_mass_kg : nullptr;
        if (!target) {
          if (!c.mass.diagonal_total_mass_kg) c.mass.diagonal_total_mass_kg = 0.0;
          target = &*c.mass.diagonal_total_mass_kg;
        }
        return Slot{target, 0.0, inf, true, false, "kg"};
      }
      case ParameterId::kMassDensity: return Slot{&c.mass.mass_density_kg_per_m3, 0.0, inf, true, false, "kg/m^3"};
      default: break;
    }
    return no_parameter("mass");
  }
  return make_error(ErrorCode::kInvalidArgument, fmt::format("no component '{}' (parameters: {})", component,
                                                      fmt::join(parameter_names(c), ", ")),
                    c.name);
}

}  // namespace

std::string_view parameter_name(ParameterId id) {
  const auto i = static_cast<std::size_t>(id);
  return i < kNames.size() ? kNames[i] : std::string_view("?");
}

Expected<ParameterId> parameter_id(std::string_view name) {
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if (kNames[i] == name) return static_cast<ParameterId>(i);
  }
  // The closest names: those within a third of the name's length in edits (at least 2).
  std::vector<std::string_view> closest;
  const std::size_t allowed = std::max<std::size_t>(2, name.size() / 3);
  std::size_t best = allowed + 1;
  for (std::string_view candidate : kNames) {
    const std::size_t d = edit_distance(name, candidate);
    if (d > allowed || d > best) continue;
    if (d < best) closest.clear();
    best = d;
    closest.push_back(candidate);
  }
  return make_error(ErrorCode::kInvalidArgument,
                    closest.empty() ? fmt::format("no parameter '{}'", name)
                                    : fmt::format("no parameter '{}' (closest: {})", name, fmt::join(closest, ", ")));
}

namespace {

Expected<void> set_slot(ModelConfig& config, std::string_view component, ParameterId id, std::string_view parameter,
                        double value) {
  ModelConfig trial = config;  // untouched on any error (a totalMass may add an optional)
  int integer_storage = 0;
  double scratch = 0.0;
  auto slot = find_slot(trial, component, id, parameter, integer_storage, scratch);
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

Expected<double> get_slot(const ModelConfig& config, std::string_view component, ParameterId id, std::string_view parameter) {
  ModelConfig copy = config;
  int integer_storage = 0;
  double scratch = 0.0;
  auto slot = find_slot(copy, component, id, parameter, integer_storage, scratch);
  if (!slot) return std::unexpected(slot.error());
  return *slot->value;
}

}  // namespace

Expected<void> set_parameter(ModelConfig& config, std::string_view component, ParameterId id, double value) {
  return set_slot(config, component, id, parameter_name(id), value);
}

Expected<double> get_parameter(const ModelConfig& config, std::string_view component, ParameterId id) {
  return get_slot(config, component, id, parameter_name(id));
}

// By name: the name is mapped to its id once; a name that is no parameter's is still looked up
// in the component, whose error says which component has no such parameter.
Expected<void> set_parameter(ModelConfig& config, std::string_view component, std::string_view parameter, double value) {
  const auto id = parameter_id(parameter);
  return set_slot(config, component, id ? *id : kNoId, parameter, value);
}

Expected<double> get_parameter(const ModelConfig& config, std::string_view component, std::string_view parameter) {
  const auto id = parameter_id(parameter);
  return get_slot(config, component, id ? *id : kNoId, parameter);
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
