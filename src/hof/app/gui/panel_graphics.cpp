// The Graphics panel: the project's render mode, colouring, material and lights, the view
// kept in the project, and the window's debug views.
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <iterator>

#include "hof/app/gui/panels.h"

namespace hof::app::gui {

GuiCommands graphics_panel(const WorldView& w, ViewOptions& view) {
  GuiCommands out;
  const auto set = [&](const char* element, const char* attribute, const std::string& value) {
    out.push_back(action::SetAttribute{element, attribute, value});
  };
  const scene::GraphicsSetup& g = w.project.graphics;
  const char* modes[] = {"shaded", "wireframe", "shaded+wireframe", "points"};
  int mode = static_cast<int>(std::find(std::begin(modes), std::end(modes), g.render_mode) - std::begin(modes));
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("renderMode", &mode, modes, 4)) set("graphics", "renderMode", modes[mode]);
  const char* colourings[] = {"material", "displacement", "strain", "stress"};
  int colouring = g.color_by == "displacement" ? 1 : g.color_by == "strain" ? 2 : g.color_by == "stress" ? 3 : 0;
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("colorBy", &colouring, colourings, 4)) set("graphics", "colorBy", colourings[colouring]);
  float diffuse[3] = {static_cast<float>(g.diffuse_color.x()), static_cast<float>(g.diffuse_color.y()), static_cast<float>(g.diffuse_color.z())};
  if (ImGui::ColorEdit3("diffuseColor", diffuse)) {
    set("graphics/material", "diffuseColor", fmt::format("{} {} {}", diffuse[0], diffuse[1], diffuse[2]));
  }
  float shininess = static_cast<float>(g.shininess), transparency = static_cast<float>(g.transparency);
  ImGui::SetNextItemWidth(200);
  if (ImGui::SliderFloat("shininess", &shininess, 0.0f, 1.0f)) set("graphics/material", "shininess", number_text(shininess));
  ImGui::SetNextItemWidth(200);
  if (ImGui::SliderFloat("transparency", &transparency, 0.0f, 0.9f)) set("graphics/material", "transparency", number_text(transparency));
  if (ImGui::TreeNode("Lights")) {
    bool headlight = g.headlight;
    if (ImGui::Checkbox("headlight", &headlight)) set("graphics/light", "headlight", headlight ? "true" : "false");
    float head = static_cast<float>(g.headlight_intensity), key = static_cast<float>(g.light_intensity),
          ambient = static_cast<float>(g.ambient_intensity);
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("headlightIntensity", &head, 0.0f, 1.0f)) set("graphics/light", "headlightIntensity", number_text(head));
    float direction[3] = {static_cast<float>(g.light_direction.x()), static_cast<float>(g.light_direction.y()),
                          static_cast<float>(g.light_direction.z())};
    ImGui::SetNextItemWidth(200);
    if (ImGui::SliderFloat3("direction", direction, -1.0f, 1.0f) && Eigen::Vector3f(direction[0], direction[1], direction[2]).norm() > 1e-3f) {
      set("graphics/light", "direction", fmt::format("{} {} {}", direction[0], direction[1], direction[2]));
    }
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("intensity", &key, 0.0f, 1.0f)) set("graphics/light", "intensity", number_text(key));
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("ambientIntensity", &ambient, 0.0f, 1.0f)) set("graphics/light", "ambientIntensity", number_text(ambient));
    ImGui::TreePop();
  }
  if (ImGui::Button("Reset view")) out.push_back(action::ResetCamera{});
  ImGui::SameLine();
  if (ImGui::Button("Keep this view in the project")) {
    const Vec3 eye = w.camera.eye(), target = w.camera.target();
    set("graphics", "viewpoint", fmt::format("{} {} {}", eye.x(), eye.y(), eye.z()));
    set("graphics", "lookAt", fmt::format("{} {} {}", target.x(), target.y(), target.z()));
  }
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
