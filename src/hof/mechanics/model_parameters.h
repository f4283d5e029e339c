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

#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/mechanical_model.h"

namespace hof::mechanics {

/// Sets `parameter` of `component` in `config` to `value` after checking its range. Errors
/// (kInvalidArgument) name the component, the parameter and the allowed range, and leave
/// `config` unchanged.
[[nodiscard]] Expected<void> set_parameter(ModelConfig& config, std::string_view component, std::string_view parameter,
                                           double value);

/// The current value of a parameter (same names as set_parameter).
[[nodiscard]] Expected<double> get_parameter(const ModelConfig& config, std::string_view component,
                                             std::string_view parameter);

/// "component/parameter" pairs that set_parameter accepts for this model (for help texts and
/// the window's scene tree); the model's own parameters have an empty component ("/dt").
[[nodiscard]] std::vector<std::string> parameter_names(const ModelConfig& config);

}  // namespace hof::mechanics
