#include "hof/scene/model_parameters.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstdint>
#include <optional>

#include "hof/core/text.h"
#include "hof/coupling/session.h"

namespace hof::scene {

namespace {

using mechanics::ComponentKind;
using mechanics::ComponentRef;
using mechanics::ParameterId;
using mechanics::ParameterRef;

// The component of a scene's name, in lookup order; nullopt when none has it.
std::optional<ComponentRef> find_component(const mechanics::ModelConfig& c, std::string_view component) {
  if (component.empty()) return ComponentRef{ComponentKind::kModel, 0};
  for (std::uint32_t i = 0; i < c.force_fields.size(); ++i) {
    if (c.force_fields[i].name == component) return ComponentRef{ComponentKind::kForceField, i};
  }
  if (c.ode.name == component) return ComponentRef{ComponentKind::kOdeSolver, 0};
  if (c.linear.name == component) return ComponentRef{ComponentKind::kLinearSolver, 0};
  if (c.mass.name == component) return ComponentRef{ComponentKind::kMass, 0};
  return std::nullopt;
}

}  // namespace

Expected<ParameterId> parameter_id(std::string_view name) {
  for (std::size_t i = 0; i < mechanics::kParameterCount; ++i) {
    const auto id = static_cast<ParameterId>(i);
    if (mechanics::parameter_name(id) == name) return id;
  }
  // The closest names: those within a third of the name's length in edits (at least 2).
  std::vector<std::string_view> closest;
  const std::size_t allowed = std::max<std::size_t>(2, name.size() / 3);
  std::size_t best = allowed + 1;
  for (std::size_t i = 0; i < mechanics::kParameterCount; ++i) {
    const std::string_view candidate = mechanics::parameter_name(static_cast<ParameterId>(i));
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

Expected<ParameterRef> resolve_parameter(const mechanics::ModelConfig& config, std::string_view component,
                                         std::string_view parameter) {
  const auto found = find_component(config, component);
  if (!found) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("no component '{}' (parameters: {})", component, fmt::join(parameter_names(config), ", ")),
        config.name);
  }
  const auto id = parameter_id(parameter);
  if (!id) {
    // A name that is no parameter's at all: the component's kind, and the closest names.
    std::string closest;
    const std::string& why = id.error().message;
    if (const auto at = why.find(" (closest"); at != std::string::npos) closest = why.substr(at);
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{} '{}' has no parameter '{}'{}", mechanics::component_kind_name(found->kind),
                                  component, parameter, closest),
                      config.name);
  }
  const ParameterRef ref{*found, *id};
  // A parameter this component does not have (the model lists what each component has).
  if (const auto accepted = mechanics::parameter_refs(config); std::ranges::find(accepted, ref) == accepted.end()) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("{} '{}' has no parameter '{}'", mechanics::component_kind_name(found->kind), component, parameter),
        config.name);
  }
  return ref;
}

std::string parameter_path(const mechanics::ModelConfig& config, ParameterRef ref) {
  return fmt::format("{}/{}", mechanics::component_name(config, ref.component), mechanics::parameter_name(ref.id));
}

std::vector<std::string> parameter_names(const mechanics::ModelConfig& config) {
  const std::vector<ParameterRef> refs = mechanics::parameter_refs(config);
  std::vector<std::string> names;
  for (const ParameterRef& ref : refs) {
    if (ref.component.kind == ComponentKind::kModel) names.emplace_back(mechanics::parameter_name(ref.id));
  }
  for (const ParameterRef& ref : refs) {
    if (ref.component.kind != ComponentKind::kModel) names.push_back(parameter_path(config, ref));
  }
  for (const ParameterRef& ref : refs) {
    if (ref.component.kind == ComponentKind::kModel) names.push_back(parameter_path(config, ref));
  }
  return names;
}

Expected<void> set_parameter(mechanics::ModelConfig& config, std::string_view component, std::string_view parameter,
                             double value) {
  auto ref = resolve_parameter(config, component, parameter);
  if (!ref) return std::unexpected(ref.error());
  return mechanics::set_parameter(config, *ref, value);
}

Expected<double> get_parameter(const mechanics::ModelConfig& config, std::string_view component,
                               std::string_view parameter) {
  auto ref = resolve_parameter(config, component, parameter);
  if (!ref) return std::unexpected(ref.error());
  return mechanics::get_parameter(config, *ref);
}

Expected<coupling::BodyId> body_id(const coupling::Session& session, std::string_view body) {
  std::string names;
  for (std::size_t i = 0; i < session.body_count(); ++i) {
    if (session.body(i).name == body) return static_cast<coupling::BodyId>(i);
    names += (names.empty() ? "" : ", ") + session.body(i).name;
  }
  return make_error(ErrorCode::kInvalidArgument,
                    fmt::format("no body '{}' (bodies: {})", body, names.empty() ? "none" : names));
}

Expected<coupling::command::SetParameter> parameter_command(const coupling::Session& session, std::string_view body,
                                                            std::string_view component, std::string_view parameter,
                                                            double value) {
  const auto id = body_id(session, body);
  if (!id) return std::unexpected(id.error());
  const auto config = session.body_config(*id);
  if (!config) return std::unexpected(config.error());
  const auto ref = resolve_parameter(*config, component, parameter);
  if (!ref) return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}': {}", body, ref.error().message));
  return coupling::command::SetParameter{*id, *ref, value};
}

Expected<double> session_parameter(const coupling::Session& session, std::string_view body, std::string_view component,
                                   std::string_view parameter) {
  const auto id = body_id(session, body);
  if (!id) return std::unexpected(id.error());
  const auto config = session.body_config(*id);
  if (!config) return std::unexpected(config.error());
  const auto ref = resolve_parameter(*config, component, parameter);
  if (!ref) return std::unexpected(ref.error());
  return session.parameter(*id, *ref);
}

std::vector<ParameterChange> parameter_changes(const coupling::Session& session, bool with_queued) {
  const std::vector<coupling::ParameterChange> changes = session.parameter_changes(with_queued);
  // Each body's configuration once (a copy of its mesh: not one per change).
  std::vector<std::optional<mechanics::ModelConfig>> configs(session.body_count());
  std::vector<ParameterChange> named;
  named.reserve(changes.size());
  for (const coupling::ParameterChange& change : changes) {
    const auto i = static_cast<std::size_t>(change.body);
    if (!configs[i]) {
      // A change is recorded for a body with mechanics only, which always has a configuration.
      auto config = session.body_config(change.body);
      configs[i] = config ? std::move(*config) : mechanics::ModelConfig{};
    }
    named.push_back(ParameterChange{session.body(i).name,
                                    std::string(mechanics::component_name(*configs[i], change.parameter.component)),
                                    std::string(mechanics::parameter_name(change.parameter.id)), change.value});
  }
  return named;
}

}  // namespace hof::scene
