// The Graphics panel: the project's render mode, colouring, material and lights, the view
// kept in the project, and the window's debug views.
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <charconv>
#include <iterator>
#include <optional>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

namespace {

/// A float as the project file writes it and reads it back (its shortest text), so that a
/// colour picked here is the number a saved project holds.
double as_written(float v) {
  const std::string text = fmt::format("{}", v);
  double out = 0.0;
  std::from_chars(text.data(), text.data() + text.size(), out);
  return out;
}

std::string joined(const float (&v)[3]) { return fmt::format("{} {} {}", v[0], v[1], v[2]); }
Vec3 as_written(const float (&v)[3]) { return Vec3(as_written(v[0]), as_written(v[1]), as_written(v[2])); }

}  // namespace

GuiCommands graphics_panel(const WorldView& w, ViewOptions& view) {
  GuiCommands out;
  // The settings changed this frame, as one typed edit of the project's graphics (with each
  // change named as the project file names it, for a recording's events).
  const scene::GraphicsSetup& g = w.project.graphics;
  std::optional<action::SetGraphics> edit;
  const auto change = [&](const char* element, const char* attribute, const std::string& value, const auto& apply) {
    if (!edit) edit = action::SetGraphics{g, {}};
    apply(edit->graphics);
    edit->settings.push_back(fmt::format("{}@{} {}", element, attribute, value));
  };
  // The combos list the enums' values in their order, by the file's names (views of string
  // literals: null-terminated).
  const char* modes[4];
  for (int i = 0; i < 4; ++i) modes[i] = scene::render_mode_name(static_cast<scene::RenderMode>(i)).data();
  int mode = static_cast<int>(g.render_mode);
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("renderMode", &mode, modes, 4)) {
    const auto chosen = static_cast<scene::RenderMode>(mode);
    change("graphics", "renderMode", std::string(scene::render_mode_name(chosen)),
           [&](scene::GraphicsSetup& n) { n.render_mode = chosen; });
  }
  const char* colourings[4];
  for (int i = 0; i < 4; ++i) colourings[i] = scene::color_by_name(static_cast<scene::ColorBy>(i)).data();
  int colouring = static_cast<int>(g.color_by);
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("colorBy", &colouring, colourings, 4)) {
    const auto chosen = static_cast<scene::ColorBy>(colouring);
    change("graphics", "colorBy", std::string(scene::color_by_name(chosen)),
           [&](scene::GraphicsSetup& n) { n.color_by = chosen; });
  }
  float diffuse[3] = {static_cast<float>(g.diffuse_color.x()), static_cast<float>(g.diffuse_color.y()),
                      static_cast<float>(g.diffuse_color.z())};
  if (ImGui::ColorEdit3("diffuseColor", diffuse)) {
    change("graphics/material", "diffuseColor", joined(diffuse),
           [&](scene::GraphicsSetup& n) { n.diffuse_color = as_written(diffuse); });
  }
  const auto unit = [&](const char* element, const char* attribute, float v, double scene::GraphicsSetup::*field) {
    change(element, attribute, number_text(v), [&](scene::GraphicsSetup& n) { n.*field = v; });
  };
  float shininess = static_cast<float>(g.shininess), transparency = static_cast<float>(g.transparency);
  ImGui::SetNextItemWidth(200);
  if (ImGui::SliderFloat("shininess", &shininess, 0.0f, 1.0f))
    unit("graphics/material", "shininess", shininess, &scene::GraphicsSetup::shininess);
  ImGui::SetNextItemWidth(200);
  if (ImGui::SliderFloat("transparency", &transparency, 0.0f, 0.9f)) {
    unit("graphics/material", "transparency", transparency, &scene::GraphicsSetup::transparency);
  }
  if (ImGui::TreeNode("Lights")) {
    bool headlight = g.headlight;
    if (ImGui::Checkbox("headlight", &headlight)) {
      change("graphics/light", "headlight", headlight ? "true" : "false",
             [&](scene::GraphicsSetup& n) { n.headlight = headlight; });
    }
    float head = static_cast<float>(g.headlight_intensity), key = static_cast<float>(g.light_intensity),
          ambient = static_cast<float>(g.ambient_intensity);
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("headlightIntensity", &head, 0.0f, 1.0f)) {
      unit("graphics/light", "headlightIntensity", head, &scene::GraphicsSetup::headlight_intensity);
    }
    float direction[3] = {static_cast<float>(g.light_direction.x()), static_cast<float>(g.light_direction.y()),
                          static_cast<float>(g.light_direction.z())};
    ImGui::SetNextItemWidth(200);
    if (ImGui::SliderFloat3("direction", direction, -1.0f, 1.0f) &&
        Eigen::Vector3f(direction[0], direction[1], direction[2]).norm() > 1e-3f) {
      change("graphics/light", "direction", joined(direction),
             [&](scene::GraphicsSetup& n) { n.light_direction = as_written(direction); });
    }
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("intensity", &key, 0.0f, 1.0f))
      unit("graphics/light", "intensity", key, &scene::GraphicsSetup::light_intensity);
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("ambientIntensity", &ambient, 0.0f, 1.0f)) {
      unit("graphics/light", "ambientIntensity", ambient, &scene::GraphicsSetup::ambient_intensity);
    }
    ImGui::TreePop();
  }
  if (ImGui::Button("Reset view")) out.push_back(action::ResetCamera{});
  ImGui::SameLine();
  if (ImGui::Button("Keep this view in the project")) {
    const Vec3 eye = w.camera.eye(), target = w.camera.target();
    change("graphics", "viewpoint", fmt::format("{} {} {}", eye.x(), eye.y(), eye.z()),
           [&](scene::GraphicsSetup& n) { n.viewpoint_m = eye; });
    change("graphics", "lookAt", fmt::format("{} {} {}", target.x(), target.y(), target.z()),
           [&](scene::GraphicsSetup& n) { n.look_at_m = target; });
  }
  if (edit) out.push_back(std::move(*edit));
  ImGui::Separator();
  ImGui::TextDisabled("debug views");
  ImGui::Checkbox("bound-tree boxes", &view.show_bound_tree);
  if (view.show_bound_tree) {
    ImGui::SameLine();
    ImGui::SetNextItemWidth(100);
    ImGui::SliderInt("depth", &view.bound_tree_depth, 0, 12);
  }
  ImGui::Checkbox("contact triangle", &view.show_contact_triangle);
  ImGui::Checkbox("fixed nodes", &view.show_fixed_nodes);
  ImGui::Checkbox("material regions", &view.show_regions);
  ImGui::Checkbox("device position", &view.show_device);
  ImGui::SetNextItemWidth(200);
  ImGui::SliderFloat("force arrow (m/N, 0 = auto)", &view.arrow_m_per_n, 0.0f, 0.1f, "%.3f");
  return out;
}

}  // namespace hof::app::gui
