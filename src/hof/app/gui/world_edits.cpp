// The window's edits: a setting by the project file's names (applied through the session's
// seam, kept in the project), a structural change of the scene (the models rebuilt from the
// project and swapped in), a component switched, the force effects replaced.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "hof/app/gui/detail/component_switch.h"
#include "hof/app/gui/detail/gui_window.h"
#include "hof/app/gui/detail/panels.h"
#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/scene/device_config.h"
#include "hof/scene/model_parameters.h"
#include "hof/scene/sofa_scene_edit.h"

namespace hof::app::gui {

Expected<void> GuiWindow::apply_set(const std::string& element, const std::string& attribute,
                                    const std::string& value) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  const std::string name = element + "@" + attribute;
  // mechanics/BODY/COMPONENT@PARAMETER (or mechanics/BODY@PARAMETER for the model's own).
  if (element == "mechanics" || element.starts_with("mechanics/"))
    return set_mechanics_parameter(element, attribute, value);
  // The text parsed once, by the project file's names and checks, into a typed edit.
  auto edit = scene::parse_project_edit(project_, file_, element, attribute, value);
  if (!edit) return std::unexpected(edit.error());
  if (auto ok = apply_project_edit(*edit, name); !ok) return ok;
  if (recording_) recording_->events.push_back(fmt::format("{:.3f}: set {} {}", recording_->seconds(), name, value));
  dirty_ = true;
  return {};
}

Expected<void> GuiWindow::apply_project_edit(const scene::ProjectEdit& edit, const std::string& name) {
  scene::HofProject next = project_;
  scene::apply_edit(next, edit);
  if (std::holds_alternative<scene::project_edit::Calibration>(edit)) {
    const haptics::Calibration c = scene::session_config(next).haptics.calibration;
    if (!calibration_pending_) pending_calibration_ = calibration_;  // in force until the loop has the new one
    if (auto ok = session_->submit(coupling::command::SetCalibration{c}); !ok) return ok;
    calibration_ = c;
    // The mouse stylus stays where it is in the world: its device position follows once the
    // haptic loop has the new calibration (before that, a new device position read through the
    // old one would put the stylus elsewhere for a few ticks).
    calibrations_submitted_ += 1;
    calibration_pending_ = true;
  } else if (std::holds_alternative<scene::project_edit::Device>(edit)) {
    if (auto ok = set_device(next, name); !ok) return ok;
  } else if (const auto* needle = std::get_if<scene::project_edit::Needle>(&edit)) {
    // Taken by the needle's next tick: it keeps its place and phase.
    if (!needle_)
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("'{}': no needle is mounted (script: needle on)", name));
    if (auto ok = needle_->configure(needle->needle); !ok) return ok;
  } else {
    std::vector<std::string> names;
    for (const BodyView& b : bodies_) names.push_back(b.name);
    const auto commands = scene::live_commands(next, edit, names);
    if (!commands) report(fmt::format("'{}' is saved; it takes effect when the project is reopened", name), false);
    for (const coupling::Command& c : commands.value_or(std::vector<coupling::Command>{})) {
      if (auto ok = session_->submit(c); !ok) return ok;
    }
  }
  project_ = std::move(next);
  return {};
}

Expected<void> GuiWindow::set_mechanics_parameter(const std::string& element, const std::string& attribute,
                                                  const std::string& value) {
  const std::string name = element + "@" + attribute;
  const std::string rest = element.size() > 10 ? element.substr(10) : std::string();
  const std::size_t slash = rest.find('/');
  const std::string body = rest.substr(0, slash);
  const std::string component = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
  if (body.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("'{}': name a body: mechanics/BODY/COMPONENT@PARAMETER", name));
  double v = 0.0;
  const auto parsed = std::from_chars(value.data(), value.data() + value.size(), v);
  if (parsed.ec != std::errc() || parsed.ptr != value.data() + value.size() || !std::isfinite(v)) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("'{}': '{}' is not a number", name, value));
  }
  auto command = scene::parameter_command(*session_, body, component, attribute, v);
  if (!command) {
    Error e = command.error();
    e.message = fmt::format("'{}': {}", name, e.message);
    return std::unexpected(e);
  }
  return set_parameter(*command, name);
}

Expected<void> GuiWindow::set_parameter(const coupling::command::SetParameter& set, const std::string& name) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  const auto i = static_cast<std::size_t>(set.body);
  if (i >= bodies_.size() || !bodies_[i].structure)
    return make_error(ErrorCode::kInvalidArgument, fmt::format("no deformable body #{}", i));
  BodyView& b = bodies_[i];
  // Named as the body's model names it now (for the project's <set> and the recording).
  const std::string path = scene::parameter_path(current_config(b), set.parameter);
  const std::size_t slash = path.find('/');
  const std::string component = path.substr(0, slash);
  const std::string parameter = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string setting = fmt::format(
      "{}@{}", component.empty() ? "mechanics/" + b.name : "mechanics/" + b.name + "/" + component, parameter);
  if (auto ok = session_->submit(set); !ok) {
    Error e = ok.error();
    e.message = fmt::format("'{}': {}", name.empty() ? setting : name, e.message);
    return std::unexpected(e);
  }
  b.stress.reset();  // its moduli may have changed
  submitted_changes_.push_back(scene::ParameterChange{b.name, component, parameter, set.value});
  if (recording_) {
    recording_->events.push_back(
        fmt::format("{:.3f}: set {} {}", recording_->seconds(), setting, number_text(set.value)));
  }
  dirty_ = true;
  return {};
}

Expected<void> GuiWindow::set_device(const scene::HofProject& next, const std::string& name) {
  // Opened here so that the window keeps a handle on a mouse stylus.
  const std::string spec = next.device == "auto" ? std::string("mouse") : next.device;
  if (spec.starts_with("openhaptics")) {
    // Its servo loop must be the haptic loop's clock from the start.
    return make_error(ErrorCode::kUnsupported,
                      fmt::format("'{}': an OpenHaptics device drives the haptic loop from its own servo "
                                  "loop: open the window with it (hof gui FILE --device {})",
                                  name, spec));
  }
  auto config = scene::parse_device_spec(spec);
  if (!config) return std::unexpected(config.error());
  auto opened = scene::open_device(spec);
  if (!opened) return std::unexpected(opened.error());
  std::shared_ptr<haptics::Device> device(std::move(*opened));
  if (auto ok = session_->submit(coupling::command::SetDevice{*config, spec, device}); !ok) return ok;
  mouse_ = dynamic_cast<haptics::MouseDevice*>(device.get());  // the session keeps the device alive
  if (mouse_) mouse_->place((mouse_calibration().position.inverse() * mouse_world_.homogeneous()).head<3>());
  device_spec_ = spec;
  max_force_n_ = device->spec().max_force_n;
  workspace_radius_m_ = device->spec().workspace_radius_m;
  return {};
}

Expected<void> GuiWindow::change_structure(const std::optional<scene::SceneEdit>& edit,
                                           const std::optional<std::vector<scene::MaterialRegion>>& regions) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (file_.extension() == ".x3d") {
    return make_error(ErrorCode::kUnsupported,
                      "the scene tree edits SOFA scenes; an X3D scene's bodies are edited in its file", file_.string());
  }
  scene::HofProject next = project_;
  // The values changed so far go with the new models (the seam forgets them at the switch),
  // those still queued too.
  scene::record_parameters(next, scene::parameter_changes(*session_));
  scene::record_parameters(next, submitted_changes_);
  if (next.mechanics_inline.empty()) {
    // From now on the project holds its scene (the file it came from is left as it was).
    auto text = scene::inline_scene(scene::scene_file(project_, file_), file_.parent_path());
    if (!text) return std::unexpected(text.error());
    next.mechanics_inline = std::move(*text);
    next.mechanics_scene.clear();
  }
  if (edit) {
    auto text = scene::edit_scene(next.mechanics_inline, *edit);
    if (!text) return std::unexpected(text.error());
    next.mechanics_inline = std::move(*text);
    if (edit->action != scene::SceneEdit::Action::kAdd) {
      std::erase_if(next.parameters, [&](const scene::ParameterChange& c) {
        return c.body == edit->node && c.component == edit->component;
      });
    }
  }
  if (regions) next.regions = *regions;
  auto world = scene::build_world(next, file_, "mouse");
  if (!world) {
    Error e = world.error();
    e.message = "the change is not made: " + e.message;
    return std::unexpected(e);
  }
  for (const coupling::SessionBody& b : world->bodies) {
    if (!b.config) continue;
    const auto id = scene::body_id(*session_, b.name);
    if (auto ok = id ? session_->submit(coupling::command::SetModel{*id, *b.config, nullptr})
                     : Expected<void>(std::unexpected(id.error()));
        !ok) {
      Error e = ok.error();
      e.message = "the change is not made: " + e.message;
      return std::unexpected(e);
    }
  }
  for (const coupling::SessionBody& b : world->bodies) {
    for (BodyView& v : bodies_) {
      if (v.name == b.name && b.config) v.set_structure(*b.config);
    }
  }
  for (const std::string& w : world->warnings) {
    if (warned_.insert(w).second) report("warning: " + w, false);  // each once, not with every edit
  }
  if (edit) {
    const char* verb = edit->action == scene::SceneEdit::Action::kReplace ? "is now"
                       : edit->action == scene::SceneEdit::Action::kAdd   ? "added:"
                                                                          : "removed";
    report(fmt::format("{}/{} {} {}", edit->node, edit->component, verb, edit->type), false);
  }
  if (recording_) {
    recording_->events.push_back(fmt::format(
        "{:.3f}: {}", recording_->seconds(),
        edit ? fmt::format("scene edit {}/{}", edit->node, edit->component) : std::string("material regions")));
  }
  project_ = std::move(next);
  submitted_changes_.clear();
  dirty_ = true;
  return {};
}

Expected<void> GuiWindow::switch_component(const std::string& body, const std::string& component,
                                           const std::string& choice) {
  const auto b = std::find_if(bodies_.begin(), bodies_.end(), [&](const BodyView& v) { return v.name == body; });
  if (b == bodies_.end()) return make_error(ErrorCode::kInvalidArgument, fmt::format("no body '{}'", body));
  if (!b->structure) return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}' is rigid", body));
  auto edit = switch_edit(current_config(*b), body, component, choice);
  if (!edit) return std::unexpected(edit.error());
  auto done = change_structure(*edit, std::nullopt);
  if (!done && (choice == "CGLinearSolver" || choice == "SparseLDLSolver")) {
    // The scene had no linear solver (its defaults were shown): add one.
    edit->action = scene::SceneEdit::Action::kAdd;
    return change_structure(*edit, std::nullopt);
  }
  return done;
}

Expected<void> GuiWindow::edit_project(const action::EditProject& edit) {
  // A typed edit of the project in memory, checked as the file's reader checks what it reads;
  // the session's commands that carry it follow (apply_project_edit).
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  const std::string name = edit.settings.empty() ? std::string("haptics") : edit.settings.front();
  if (auto ok = scene::check_edit(project_, edit.edit); !ok) {
    Error e = ok.error();
    e.message = fmt::format("'{}': {}", name, e.message);
    return std::unexpected(e);
  }
  if (std::holds_alternative<scene::project_edit::Tool>(edit.edit)) {
    scene::HofProject next = project_;
    scene::apply_edit(next, edit.edit);
    return set_tool(next, edit.settings);
  }
  if (auto ok = apply_project_edit(edit.edit, name); !ok) return ok;
  note_settings(edit.settings);
  return {};
}

Expected<void> GuiWindow::set_tool(const scene::HofProject& next, const std::vector<std::string>& settings) {
  if (file_.extension() == ".x3d")
    return make_error(ErrorCode::kUnsupported, "a tool is mounted in a .hof project (save the scene as one)");
  // The tool is part of the world the session was made with (the haptic loop's tool, the
  // tissue coupling): the world is opened again with it, as for the needle. A tool that does
  // not build (a mesh not found or not closed) leaves the world as it was.
  if (auto ok = reopen_with(next); !ok) {
    Error e = ok.error();
    e.message = "the tool is not mounted: " + e.message;
    return std::unexpected(e);
  }
  note_settings(settings);
  report(project_.tool ? fmt::format("the stylus carries a {} (Tool panel; turn it with Alt + left drag)",
                                     procedures::shape_name(project_.tool->shape))
                       : std::string("the stylus is the point proxy again"),
         false);
  return {};
}

Expected<void> GuiWindow::set_contact_pair(const coupling::command::SetContactPair& pair) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (auto ok = session_->submit(pair); !ok) return ok;
  const auto a = static_cast<std::int32_t>(std::min(pair.a, pair.b));
  const auto b = static_cast<std::int32_t>(std::max(pair.a, pair.b));
  if (pair.enabled) {
    disabled_pairs_.erase(BodyPair{a, b});
  } else {
    disabled_pairs_.insert(BodyPair{a, b});
  }
  const std::string& name_a = bodies_[static_cast<std::size_t>(a)].name;
  const std::string& name_b = bodies_[static_cast<std::size_t>(b)].name;
  if (project_.contact) {
    // The project's <contact><pair enabled="false"> list, by name: a save keeps the switch.
    auto& pairs = project_.contact->disabled_pairs;
    std::erase_if(pairs, [&](const auto& p) {
      return (p.first == name_a && p.second == name_b) || (p.first == name_b && p.second == name_a);
    });
    if (!pair.enabled) pairs.emplace_back(name_a, name_b);
    note_settings({fmt::format("contact/pair {} {} {}", name_a, name_b, pair.enabled ? "on" : "off")});
  }
  report(fmt::format("contact {} - {} {}{}", name_a, name_b, pair.enabled ? "on" : "off",
                     project_.contact ? "" : " (the scene's collision pipeline sets its pairs: not saved)"),
         false);
  return {};
}

Expected<void> GuiWindow::set_graphics(const action::SetGraphics& edit) {
  // A typed edit of the project in memory: checked as a file's <graphics> is, drawn by the
  // window only (nothing for the session).
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  const std::string name = edit.settings.empty() ? std::string("graphics") : edit.settings.front();
  if (auto ok = scene::check_graphics(edit.graphics); !ok) {
    Error e = ok.error();
    e.message = fmt::format("'{}': {}", name, e.message);
    return std::unexpected(e);
  }
  if (auto ok = apply_project_edit(scene::project_edit::Graphics{edit.graphics}, name); !ok) return ok;
  note_settings(edit.settings);
  return {};
}

Expected<void> GuiWindow::set_surface(const action::SetSurface& edit) {
  // A typed edit of the project in memory; the bodies without a surface of their own take it
  // through the seam.
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  const std::string name = edit.settings.empty() ? std::string("haptics/surface") : edit.settings.front();
  if (auto ok = haptics::validate(edit.surface); !ok) {
    Error e = ok.error();
    e.message = fmt::format("'{}': {}", name, e.message);
    return std::unexpected(e);
  }
  if (auto ok = apply_project_edit(scene::project_edit::Surface{edit.surface}, name); !ok) return ok;
  note_settings(edit.settings);
  return {};
}

Expected<void> GuiWindow::set_rendering(const action::SetRendering& edit) {
  // A typed edit of the project in memory, then the haptic loop's renderer from it.
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (!std::isfinite(edit.rendering.proxy_radius_m)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("'haptics@proxyRadius': {} is not a number", edit.rendering.proxy_radius_m));
  }
  const action::Rendering& r = edit.rendering;
  const scene::project_edit::Rendering rendering{r.renderer, r.proxy_radius_m, r.force_shading, r.touchable_face};
  if (auto ok = apply_project_edit(rendering, edit.settings.empty() ? std::string("haptics") : edit.settings.front());
      !ok)
    return ok;
  note_settings(edit.settings);
  return {};
}

void GuiWindow::note_settings(const std::vector<std::string>& settings) {
  if (recording_) {
    for (const std::string& s : settings)
      recording_->events.push_back(fmt::format("{:.3f}: set {}", recording_->seconds(), s));
  }
  dirty_ = true;
}

mechanics::ModelConfig GuiWindow::current_config(const BodyView& body) const {
  // The model as last built, with the values submitted since (all of them accepted by the
  // session's seam): what the session's own configuration holds, derived when it is needed.
  mechanics::ModelConfig c = *body.structure;
  for (const scene::ParameterChange& change : submitted_changes_) {
    if (change.body == body.name) (void)scene::set_parameter(c, change.component, change.parameter, change.value);
  }
  return c;
}

Expected<void> GuiWindow::add_component(const action::AddComponent& add) {
  const auto b = std::find_if(bodies_.begin(), bodies_.end(), [&](const BodyView& v) { return v.name == add.body; });
  if (b == bodies_.end() || !b->structure)
    return make_error(ErrorCode::kInvalidArgument, fmt::format("no deformable body '{}'", add.body));
  const mechanics::ModelConfig c = current_config(*b);
  // A name no component of the node has yet: BASE, else BASE2, BASE3, ...
  const auto unique = [&](const std::string& base) {
    std::string name = base;
    for (int n = 2;
         std::any_of(b->parameters.begin(), b->parameters.end(),
                     [&](const std::string& p) { return p.starts_with(name + "/"); }) ||
         std::any_of(c.fixed.begin(), c.fixed.end(), [&](const auto& f) { return f.name == name; }) ||
         std::any_of(c.force_fields.begin(), c.force_fields.end(), [&](const auto& f) { return f.name == name; });
         ++n) {
      name = base + std::to_string(n);
    }
    return name;
  };
  const auto [young, poisson] = elastic_moduli(c);
  scene::SceneEdit edit{scene::SceneEdit::Action::kAdd, add.body, "", "", {}};
  switch (add.kind) {
    case action::AddComponent::Kind::kTetrahedronFem:
      edit.component = unique("FEM");
      edit.type = "TetrahedronFEMForceField";
      edit.attributes = {{"youngModulus", fmt::format("{}", young)},
                         {"poissonRatio", fmt::format("{}", poisson)},
                         {"method", "large"}};
      break;
    case action::AddComponent::Kind::kMeshSprings: {
      edit.component = unique("springs");
      edit.type = "MeshSpringForceField";
      const double edge = mean_edge_length(c);  // per spring ~E·l; SOFA divides by l
      edit.attributes = {{"stiffness", fmt::format("{}", young * edge * edge)}};
      break;
    }
    case action::AddComponent::Kind::kPinNearStylus: {
      const double radius = add.pin_radius_m > 0.0 ? add.pin_radius_m : 0.05 * scene_size();
      std::string indices;
      for (std::size_t i = 0; i < c.positions.size(); ++i) {
        if ((c.positions[i] - last_.proxy).norm() <= radius)
          indices += (indices.empty() ? "" : " ") + std::to_string(i);
      }
      if (indices.empty()) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("no node of {} within {:.3g} of the stylus: nothing to pin", add.body, radius));
      }
      edit.component = unique("pin");
      edit.type = "FixedProjectiveConstraint";
      edit.attributes = {{"indices", indices}};
      break;
    }
  }
  return change_structure(edit, std::nullopt);
}

Expected<void> GuiWindow::add_region_at_stylus(const action::AddRegionAtStylus& add) {
  if (!last_.valid) return make_error(ErrorCode::kInvalidArgument, "the stylus has no position yet");
  const auto b = std::find_if(bodies_.begin(), bodies_.end(), [&](const BodyView& v) { return v.name == add.body; });
  if (b == bodies_.end() || !b->structure)
    return make_error(ErrorCode::kInvalidArgument, fmt::format("no deformable body '{}'", add.body));
  scene::MaterialRegion r;
  r.name = fmt::format("region{}", project_.regions.size() + 1);
  r.body = add.body;
  r.center = last_.contact ? last_.contact_point : last_.proxy;
  r.radius = add.radius_m > 0.0 ? add.radius_m : 0.1 * scene_size();
  r.young_modulus_pa = elastic_moduli(current_config(*b)).first * std::max(add.modulus_factor, 1e-3);
  std::vector<scene::MaterialRegion> regions = project_.regions;
  regions.push_back(r);
  return change_structure(std::nullopt, regions);
}

Expected<void> GuiWindow::set_effects(const haptics::ForceEffects& effects) {
  // Adding or removing an effect changes the list as a whole (one command).
  if (!session_) return {};
  if (auto ok = apply_project_edit(scene::project_edit::Effects{effects}, "haptics/effects"); !ok) return ok;
  dirty_ = true;
  return {};
}

}  // namespace hof::app::gui
