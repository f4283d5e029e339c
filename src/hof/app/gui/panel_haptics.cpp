// The Haptics panel: the device, the renderer and proxy, the calibration, the force limit,
// the surface, the options and the force effects (H3D's names).
#include <fmt/format.h>
#include <imgui.h>

#include <array>
#include <cmath>
#include <functional>
#include <optional>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

namespace {

/// The force effects: each with its settings, one removed, one added where the stylus is.
void effects_editor(const WorldView& w, GuiCommands& out) {
  ImGui::Separator();
  ImGui::TextDisabled("force effects (H3D; Enter applies)");
  // The effects' settings changed this frame, as one typed edit of the force effects (each
  // change named as the project file names it, for messages and a recording).
  std::optional<action::EditProject> edit;
  const auto set = [&](const std::string& element, const char* attribute, const std::string& value, const auto& apply) {
    if (!edit) edit = action::EditProject{scene::project_edit::Effects{w.project.effects}, {}};
    apply(std::get<scene::project_edit::Effects>(edit->edit).effects);
    edit->settings.push_back(fmt::format("{}@{} {}", element, attribute, value));
  };
  // A number or a vector of the i-th effect of a list (ForceEffects::springs, ...).
  const auto number = [&](const std::string& element, const char* attribute, auto list, std::size_t i, auto field) {
    double value = (w.project.effects.*list)[i].*field;
    ImGui::SetNextItemWidth(160);
    if (ImGui::InputDouble(attribute, &value, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue))
      set(element, attribute, number_text(value), [&](haptics::ForceEffects& f) { (f.*list)[i].*field = value; });
  };
  const auto vector = [&](const std::string& element, const char* attribute, auto list, std::size_t i, auto field) {
    const Vec3 value = (w.project.effects.*list)[i].*field;
    double v[3] = {value.x(), value.y(), value.z()};
    ImGui::SetNextItemWidth(240);
    if (ImGui::InputScalarN(attribute, ImGuiDataType_Double, v, 3, nullptr, nullptr, "%.4g",
                            ImGuiInputTextFlags_EnterReturnsTrue)) {
      set(element, attribute, fmt::format("{} {} {}", v[0], v[1], v[2]),
          [&](haptics::ForceEffects& f) { (f.*list)[i].*field = Vec3(v[0], v[1], v[2]); });
    }
  };
  using haptics::ForceEffects, haptics::SpringEffect, haptics::ViscosityEffect;
  // Adding or removing an effect changes the list as a whole (one command).
  const auto change = [&](const auto& mutate) {
    haptics::ForceEffects effects = w.project.effects;
    mutate(effects);
    out.push_back(action::SetEffects{std::move(effects)});
  };
  std::optional<std::function<void(haptics::ForceEffects&)>> pending;  // applied after the loops below
  for (std::size_t i = 0; i < w.project.effects.springs.size(); ++i) {
    const std::string element = fmt::format("haptics/effects/SpringEffect[{}]", i + 1);
    ImGui::PushID(element.c_str());
    ImGui::Text("SpringEffect %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove"))
      pending = [i](haptics::ForceEffects& f) { f.springs.erase(f.springs.begin() + static_cast<std::ptrdiff_t>(i)); };
    vector(element, "position", &ForceEffects::springs, i, &SpringEffect::position_m);
    number(element, "springConstant", &ForceEffects::springs, i, &SpringEffect::spring_constant_n_per_m);
    number(element, "startDistance", &ForceEffects::springs, i, &SpringEffect::start_distance_m);
    number(element, "escapeDistance", &ForceEffects::springs, i, &SpringEffect::escape_distance_m);
    number(element, "damping", &ForceEffects::springs, i, &SpringEffect::damping_n_s_per_m);
    ImGui::PopID();
  }
  for (std::size_t i = 0; i < w.project.effects.viscosities.size(); ++i) {
    const std::string element = fmt::format("haptics/effects/ViscosityEffect[{}]", i + 1);
    ImGui::PushID(element.c_str());
    ImGui::Text("ViscosityEffect %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove"))
      pending = [i](haptics::ForceEffects& f) {
        f.viscosities.erase(f.viscosities.begin() + static_cast<std::ptrdiff_t>(i));
      };
    number(element, "viscosity", &ForceEffects::viscosities, i, &ViscosityEffect::viscosity_pa_s);
    number(element, "radius", &ForceEffects::viscosities, i, &ViscosityEffect::radius_m);
    number(element, "dampingFactor", &ForceEffects::viscosities, i, &ViscosityEffect::damping_factor);
    bool enabled = w.project.effects.viscosities[i].enabled;
    if (ImGui::Checkbox("enabled", &enabled)) {
      set(element, "enabled", enabled ? "true" : "false", [&](ForceEffects& f) { f.viscosities[i].enabled = enabled; });
    }
    ImGui::PopID();
  }
  for (std::size_t i = 0; i < w.project.effects.constants.size(); ++i) {
    const std::string element = fmt::format("haptics/effects/ForceField[{}]", i + 1);
    ImGui::PushID(element.c_str());
    ImGui::Text("ForceField %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove"))
      pending = [i](haptics::ForceEffects& f) {
        f.constants.erase(f.constants.begin() + static_cast<std::ptrdiff_t>(i));
      };
    vector(element, "force", &ForceEffects::constants, i, &haptics::ConstantForceEffect::force_n);
    ImGui::PopID();
  }
  // New effects start where the stylus is (a spring holds it there at once) and with H3D's defaults.
  if (ImGui::SmallButton("+ spring")) {
    pending = [at = w.last.valid ? w.last.proxy : w.stylus_target](haptics::ForceEffects& f) {
      haptics::SpringEffect spring;
      spring.position_m = at;
      f.springs.push_back(spring);
    };
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("+ viscosity")) pending = [](haptics::ForceEffects& f) { f.viscosities.emplace_back(); };
  ImGui::SameLine();
  if (ImGui::SmallButton("+ force field")) pending = [](haptics::ForceEffects& f) { f.constants.emplace_back(); };
  if (edit) out.push_back(std::move(*edit));
  if (pending && w.session) change(*pending);
}

/// The project's surface (the bodies without one of their own take it).
void surface_editor(const WorldView& w, GuiCommands& out) {
  ImGui::Separator();
  ImGui::TextDisabled("surface");
  // The surface changed this frame, as one typed edit of the project's surface.
  std::optional<action::SetSurface> surface;
  const auto change = [&](const char* attribute, const std::string& value, const auto& apply) {
    if (!surface) surface = action::SetSurface{w.project.surface, {}};
    apply(surface->surface);
    surface->settings.push_back(fmt::format("haptics/surface@{} {}", attribute, value));
  };
  int kind = static_cast<int>(w.project.surface.kind);
  const char* kinds[] = {"SmoothSurface", "FrictionalSurface", "MagneticSurface"};
  ImGui::SetNextItemWidth(200);
  if (kind >= 0 && kind < 3 && ImGui::Combo("type", &kind, kinds, 3)) {
    change("type", kinds[kind], [&](haptics::SurfaceMaterial& m) { m.kind = static_cast<haptics::SurfaceKind>(kind); });
  }
  const auto number = [&](const char* label, const char* attribute, double haptics::SurfaceMaterial::*field) {
    double value = w.project.surface.*field;
    ImGui::SetNextItemWidth(200);
    if (ImGui::InputDouble(label, &value, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
      change(attribute, number_text(value), [&](haptics::SurfaceMaterial& m) { m.*field = value; });
    }
  };
  number("stiffness", "stiffness", &haptics::SurfaceMaterial::stiffness);
  number("damping (N s/m)", "damping", &haptics::SurfaceMaterial::damping_n_s_per_m);
  number("staticFriction", "staticFriction", &haptics::SurfaceMaterial::static_friction);
  number("dynamicFriction", "dynamicFriction", &haptics::SurfaceMaterial::dynamic_friction);
  bool relative = w.project.surface.use_relative_values;
  if (ImGui::Checkbox("useRelativeValues", &relative)) {
    change("useRelativeValues", relative ? "true" : "false",
           [&](haptics::SurfaceMaterial& m) { m.use_relative_values = relative; });
  }
  if (surface) out.push_back(std::move(*surface));
}

}  // namespace

GuiCommands haptics_panel(const WorldView& w, HapticsPanelState& ui) {
  GuiCommands out;
  // A typed edit of the project, named as the file names the setting (for messages and a recording).
  const auto edit = [&](scene::ProjectEdit e, const std::string& setting) {
    out.push_back(action::EditProject{std::move(e), {setting}});
  };
  const auto device = [&](const std::string& spec) {
    edit(scene::project_edit::Device{spec}, fmt::format("haptics@device {}", spec));
  };
  ImGui::Text("device: %s", w.device_spec.c_str());
  ImGui::SameLine();
  if (w.reading) {
    ImGui::TextColored(ImVec4(0.4f, 0.9f, 0.4f, 1.0f), "reading");
  } else {
    ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "no reading (absent, timed out or ended): no force");
  }
  if (w.session) {
    ImGui::TextDisabled("device limit %.3g N; %s", w.max_force_n,
                        w.mouse_stylus ? "left-drag in the view moves the stylus" : "");
  }
  std::array<char, 256>& spec = ui.device_spec;
  ImGui::SetNextItemWidth(220);
  ImGui::InputTextWithHint("##spec", "dhd, udp:5005, spacemouse, mouse", spec.data(), spec.size());
  ImGui::SameLine();
  if (ImGui::Button("Connect") && spec[0] != '\0') device(spec.data());
  // The vendors' SDKs, loaded when asked for (docs/devices.md): a clear message when absent.
  if (ImGui::Button("Force Dimension")) device("dhd");
  ImGui::SameLine();
  if (ImGui::Button("Mouse")) device("mouse");
  // The renderer's settings changed this frame, as one typed edit of the project.
  std::optional<action::SetRendering> rendering;
  const auto render = [&](const char* attribute, const std::string& value, const auto& apply) {
    if (!rendering)
      rendering = action::SetRendering{
          {w.project.renderer, w.project.proxy_radius_m, w.project.force_shading, w.project.touchable_face}, {}};
    apply(rendering->rendering);
    rendering->settings.push_back(fmt::format("haptics@{} {}", attribute, value));
  };
  int renderer = static_cast<int>(w.project.renderer);
  const char* renderers[] = {"PenaltyRenderer", "GodObjectRenderer", "RuspiniRenderer"};
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("renderer", &renderer, renderers, 3)) {
    render("renderer", renderers[renderer],
           [&](action::Rendering& r) { r.renderer = static_cast<haptics::RendererKind>(renderer); });
  }
  double radius = w.project.proxy_radius_m;
  ImGui::SetNextItemWidth(200);
  if (ImGui::InputDouble("proxyRadius (m)", &radius, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    render("proxyRadius", number_text(radius), [&](action::Rendering& r) { r.proxy_radius_m = radius; });
  }
  double limit = w.project.safety.max_force_n;
  ImGui::SetNextItemWidth(200);
  if (ImGui::TreeNode("Calibration (device -> world)")) {
    const Eigen::Matrix3d linear = w.calibration.position.topLeftCorner<3, 3>();
    const Vec3 offset = w.calibration.position.topRightCorner<3, 1>();
    ImGui::Text("scale %.4g, offset %.4g %.4g %.4g", std::cbrt(std::abs(linear.determinant())), offset.x(), offset.y(),
                offset.z());
    ImGui::TextDisabled("device workspace radius %.3g m", w.workspace_radius_m);
    const auto apply = [&](const Eigen::Matrix4d& m) {
      std::string text;
      scene::project_edit::Calibration calibration;
      for (int i = 0; i < 16; ++i) {
        text += fmt::format("{}{}", i ? " " : "", m(i / 4, i % 4));
        calibration.position[static_cast<std::size_t>(i)] = m(i / 4, i % 4);  // row-major, as the file
      }
      edit(calibration, "haptics/calibration@positionCalibration " + text);
    };
    if (ImGui::Button("Fit the workspace to the scene")) {
      // The device's reach spans the scene's bounding sphere (keeping the axes).
      Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
      const double scale = 0.5 * w.scene_size() / std::max(w.workspace_radius_m, 1e-6);
      m.topLeftCorner<3, 3>() *= scale;
      m.topRightCorner<3, 1>() = 0.5 * (w.bounds_min + w.bounds_max);
      apply(m);
    }
    ImGui::SameLine();
    if (ImGui::Button("Identity")) apply(Eigen::Matrix4d::Identity());
    ImGui::TreePop();
  }
  if (ImGui::InputDouble("force limit (N, 0: device's)", &limit, 0.0, 0.0, "%.3g",
                         ImGuiInputTextFlags_EnterReturnsTrue)) {
    edit(scene::project_edit::ForceLimit{limit}, "haptics/safety@maxForce " + number_text(limit));
  }
  bool shading = w.project.force_shading;
  if (ImGui::Checkbox("forceShading", &shading)) {
    render("forceShading", shading ? "true" : "false", [&](action::Rendering& r) { r.force_shading = shading; });
  }
  int face = static_cast<int>(w.project.touchable_face);
  const char* faces[] = {"FRONT", "BACK", "FRONT_AND_BACK"};
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("touchableFace", &face, faces, 3)) {
    render("touchableFace", faces[face],
           [&](action::Rendering& r) { r.touchable_face = static_cast<collision::TouchableFace>(face); });
  }
  if (rendering) out.push_back(std::move(*rendering));
  surface_editor(w, out);
  ImGui::Separator();
  ImGui::TextDisabled("options (saved; they apply when the project is reopened)");
  bool tree = w.project.use_bound_tree;
  if (ImGui::Checkbox("useBoundTree", &tree)) {
    edit(scene::project_edit::BoundTree{tree, w.project.max_triangles_in_leaf},
         fmt::format("haptics/options@useBoundTree {}", tree ? "true" : "false"));
  }
  effects_editor(w, out);
  return out;
}

}  // namespace hof::app::gui
