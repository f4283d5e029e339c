#pragma once
/// @file
/// Parameters of a model's components, addressed by typed references (scene/ maps a scene's
/// names, SOFA's data names, to them: scene/model_parameters.h), so that a setting can be
/// changed — by the command seam while a session runs, and by a project's overrides when it is
/// loaded — with one validation:
///   a force field (kForceField, index): stiffness, damping, restLengthScale (mesh springs);
///                                      youngModulus, poissonRatio (FEM, Neo-Hookean, membrane),
///                                      thickness, restScale (membrane)
///   the ODE solver (kOdeSolver):       rayleighStiffness, rayleighMass, matrixReuseSteps
///   the linear solver (kLinearSolver): iterations, tolerance, threshold, warmStart, ...
///   the mass (kMass):                  totalMass, massDensity
///   the model itself (kModel):         dt, maxSpeed, gravityX, gravityY, gravityZ
/// Values are SI (N/m, Pa, s, kg, kg/m³).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/mechanical_model.h"

namespace hof::mechanics {

/// The parameters a component may have, by what they are; their names (SOFA's data names)
/// are in one table (parameter_name). Which component has which is set_parameter's business.
// One line per component, as the table reads:
// clang-format off
enum class ParameterId : std::uint8_t {
  kDt, kMaxSpeed, kGravityX, kGravityY, kGravityZ,                          // the model itself
  kStiffness, kDamping, kRestLengthScale,                                   // mesh springs
  kYoungModulus, kPoissonRatio, kThickness, kRestScale,                     // FEM, Neo-Hookean, membrane
  kRayleighStiffness, kRayleighMass, kMatrixReuseSteps,                     // the ODE solver
  kIterations, kWarmStart, kCoarseCorrection, kCoarseRefreshSteps, kTolerance, kThreshold,  // the linear solver
  kTotalMass, kMassDensity,                                                 // the mass
};
// clang-format on
inline constexpr std::size_t kParameterCount = 23;

/// Which component of a model a parameter belongs to: the model itself, one of its force
/// fields (by index in ModelConfig::force_fields), its ODE solver, linear solver or mass.
/// Scenes name components; scene::resolve_parameter maps those names to these, once.
enum class ComponentKind : std::uint8_t { kModel, kForceField, kOdeSolver, kLinearSolver, kMass };
struct ComponentRef {
  ComponentKind kind{ComponentKind::kModel};
  std::uint32_t index{0};  ///< kForceField: the force field's index; else 0
  friend bool operator==(const ComponentRef&, const ComponentRef&) = default;
};
/// One parameter of one component.
struct ParameterRef {
  ComponentRef component;
  ParameterId id{ParameterId::kDt};
  friend bool operator==(const ParameterRef&, const ParameterRef&) = default;
};

/// The scene's name of a parameter ("youngModulus"), for messages (names are mapped to ids in
/// scene/, see scene::parameter_id).
[[nodiscard]] std::string_view parameter_name(ParameterId id);
/// The kind of a component as messages name it ("force field", "ODE solver", ...).
[[nodiscard]] std::string_view component_kind_name(ComponentKind kind);
/// The scene's name of a component of `config` ("" for the model itself), for messages.
[[nodiscard]] std::string_view component_name(const ModelConfig& config, ComponentRef component);

/// Sets `parameter` in `config` to `value` after checking its range. Errors
/// (kInvalidArgument) name the component, the parameter and the allowed range, and leave
/// `config` unchanged.
[[nodiscard]] Expected<void> set_parameter(ModelConfig& config, ParameterRef parameter, double value);
/// The current value of `parameter`.
[[nodiscard]] Expected<double> get_parameter(const ModelConfig& config, ParameterRef parameter);

/// The parameters set_parameter accepts for this model, in the order help texts list them
/// (the model's own first, then each component's; see scene::parameter_names).
[[nodiscard]] std::vector<ParameterRef> parameter_refs(const ModelConfig& config);

}  // namespace hof::mechanics
