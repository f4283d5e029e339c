#pragma once
/// @file
/// A scene's names for a model's parameters (SOFA's data names, "FEM" / "youngModulus") become
/// typed mechanics::ParameterRef here, once, at the edge: below scene/, a parameter is
/// addressed by what it is, not by name. And the way back, for help texts, saved projects and
/// the window's scene tree.
///
///   component = a force field's name:  stiffness, damping, restLengthScale (mesh springs);
///                                      youngModulus, poissonRatio (FEM, Neo-Hookean, membrane),
///                                      thickness, restScale (membrane)
///   component = the ODE solver's name: rayleighStiffness, rayleighMass, matrixReuseSteps
///   component = the linear solver's:   iterations, tolerance, threshold, warmStart, ...
///   component = the mass's name:       totalMass, massDensity
///   component = "" (the model itself): dt, maxSpeed, gravityX, gravityY, gravityZ

#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/command_seam.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/model_parameters.h"

namespace hof::coupling {
class Session;
}

namespace hof::scene {

/// The parameter of a scene's name; an unknown name is an error naming the closest known names.
[[nodiscard]] Expected<mechanics::ParameterId> parameter_id(std::string_view name);

/// The parameter `parameter` of `component` in `config` (components are looked up in this
/// order: force fields, ODE solver, linear solver, mass; "" is the model itself). Errors
/// (kInvalidArgument): no such component (naming the model's parameters), or the component has
/// no such parameter (naming the closest names).
[[nodiscard]] Expected<mechanics::ParameterRef> resolve_parameter(const mechanics::ModelConfig& config,
                                                                  std::string_view component,
                                                                  std::string_view parameter);

/// "component/parameter" of `ref` in `config`; the model's own parameters have an empty
/// component ("/dt").
[[nodiscard]] std::string parameter_path(const mechanics::ModelConfig& config, mechanics::ParameterRef ref);

/// "component/parameter" pairs that resolve_parameter accepts for this model (for help texts
/// and the window's scene tree): the model's own first without a component ("dt"), then each
/// component's, then the model's own again as "/dt".
[[nodiscard]] std::vector<std::string> parameter_names(const mechanics::ModelConfig& config);

/// Sets a parameter by its scene names (resolve_parameter, then mechanics::set_parameter).
[[nodiscard]] Expected<void> set_parameter(mechanics::ModelConfig& config, std::string_view component,
                                           std::string_view parameter, double value);
/// A parameter's current value by its scene names.
[[nodiscard]] Expected<double> get_parameter(const mechanics::ModelConfig& config, std::string_view component,
                                             std::string_view parameter);

/// The body of a session by its scene name; an unknown name is an error naming the bodies.
[[nodiscard]] Expected<coupling::BodyId> body_id(const coupling::Session& session, std::string_view body);

/// The command that sets a parameter of a session's body by its scene names, resolved against
/// the body's configuration as the commands accepted so far leave it. Errors: no such body, a
/// rigid body, then "body 'NAME': " and resolve_parameter's.
[[nodiscard]] Expected<coupling::command::SetParameter> parameter_command(const coupling::Session& session,
                                                                          std::string_view body,
                                                                          std::string_view component,
                                                                          std::string_view parameter, double value);
/// A parameter's value in a session (Session::parameter) by its scene names.
[[nodiscard]] Expected<double> session_parameter(const coupling::Session& session, std::string_view body,
                                                 std::string_view component, std::string_view parameter);

/// A parameter set on a body by its scene names, as a project saves it (<set body component
/// parameter value>): a project's own, or a session's change (coupling::ParameterChange) named.
struct ParameterChange {
  std::string body;
  std::string component;  ///< "" for the model's own parameters (dt, gravity, ...)
  std::string parameter;
  double value{0.0};
};
/// A session's parameter changes (Session::parameter_changes, same order) named as the
/// bodies' configurations name them: each body's configuration as the commands accepted so far
/// leave it (a change still queued behind a structural SetModel, which will drop it, is named
/// by the new configuration).
[[nodiscard]] std::vector<ParameterChange> parameter_changes(const coupling::Session& session,
                                                             bool with_queued = false);

}  // namespace hof::scene
