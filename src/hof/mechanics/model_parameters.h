#pragma once
/// @file
/// Named parameters of a model's components, as a scene names them (SOFA's data names), so
/// that a setting can be changed by name — by the command seam while a session runs, and by a
/// project's overrides when it is loaded — with one validation:
///   component = a force field's name:  stiffness, damping, restLengthScale (mesh springs);
///                                      youngModulus, poissonRatio (FEM, Neo-Hookean, membrane),
///                                      thickness (membrane)
///   component = the ODE solver's name: rayleighStiffness, rayleighMass
///   component = the linear solver's:   iterations, tolerance, threshold
///   component = the mass's name:       totalMass, massDensity
///   component = "" (the model itself): dt, maxSpeed, gravityX, gravityY, gravityZ
/// Values are SI (N/m, Pa, s, kg, kg/m³).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/mechanical_model.h"

namespace hof::mechanics {

/// The parameters a component may have, by what they are; their names (SOFA's data names)
/// are in one table (parameter_name, parameter_id). Which component has which is
/// set_parameter's business.
enum class ParameterId : std::uint8_t {
  kDt, kMaxSpeed, kGravityX, kGravityY, kGravityZ,                          // the model itself
  kStiffness, kDamping, kRestLengthScale,                                   // mesh springs
  kYoungModulus, kPoissonRatio, kThickness, kRestScale,                     // FEM, Neo-Hookean, membrane
  kRayleighStiffness, kRayleighMass, kMatrixReuseSteps,                     // the ODE solver
  kIterations, kWarmStart, kCoarseCorrection, kCoarseRefreshSteps, kTolerance, kThreshold,  // the linear solver
  kTotalMass, kMassDensity,                                                 // the mass
};
inline constexpr std::size_t kParameterCount = 23;

/// The scene's name of a parameter ("youngModulus").
[[nodiscard]] std::string_view parameter_name(ParameterId id);
/// The parameter of a scene's name, once, at the edge; an unknown name is an error naming the
/// closest known names.
[[nodiscard]] Expected<ParameterId> parameter_id(std::string_view name);

/// Sets parameter `id` of `component` in `config` to `value` after checking its range. Errors
/// (kInvalidArgument) name the component, the parameter and the allowed range, and leave
/// `config` unchanged.
[[nodiscard]] Expected<void> set_parameter(ModelConfig& config, std::string_view component, ParameterId id, double value);
/// The current value of parameter `id` of `component`.
[[nodiscard]] Expected<double> get_parameter(const ModelConfig& config, std::string_view component, ParameterId id);

/// Sets `parameter` of `component` in `config` to `value` after checking its range. Errors
/// (kInvalidArgument) name the component, the parameter and the allowed range, and leave
/// `config` unchanged.
[[nodiscard]] Expected<void> set_parameter(ModelConfig& config, std::string_view component, std::string_view parameter,
                                           double value);

/// The current value of a parameter by name (same names as set_parameter).
[[nodiscard]] Expected<double> get_parameter(const ModelConfig& config, std::string_view component,
                                             std::string_view parameter);

/// "component/parameter" pairs that set_parameter accepts for this model (for help texts and
/// the window's scene tree); the model's own parameters have an empty component ("/dt").
[[nodiscard]] std::vector<std::string> parameter_names(const ModelConfig& config);

}  // namespace hof::mechanics
