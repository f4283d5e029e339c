// The Tool panel: what the stylus carries — the point/sphere proxy, a sphere, a capsule, a
// closed mesh (procedures/shaped_tool.h) or the needle — chosen and mounted (the project's
// <tool>; the world is opened again with it, as the needle is).
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <cstring>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

namespace {

constexpr const char* kKindNames[] = {"point", "sphere", "capsule", "mesh", "needle"};

/// What the project mounts now, as the panel's choice.
ToolChoice::Kind mounted(const scene::HofProject& p) {
  if (p.needle) return ToolChoice::Kind::kNeedle;
  if (!p.tool) return ToolChoice::Kind::kPoint;
  switch (p.tool->shape) {
    case procedures::ToolShape::kSphere:
      return ToolChoice::Kind::kSphere;
    case procedures::ToolShape::kCapsule:
      return ToolChoice::Kind::kCapsule;
    case procedures::ToolShape::kMesh:
      return ToolChoice::Kind::kMesh;
  }
  return ToolChoice::Kind::kPoint;
}

/// The project's tool in words ("capsule, radius 6 mm, shaft 80 mm").
std::string described(const scene::HofProject& p) {
  if (p.needle) return "the needle (its settings: the Needle panel)";
  if (!p.tool) return "the point proxy (a sphere of the proxy's radius)";
  const procedures::ShapedToolConfig& t = *p.tool;
  switch (t.shape) {
    case procedures::ToolShape::kSphere:
      return fmt::format("a sphere, radius {:.3g} mm", 1e3 * t.radius_m);
    case procedures::ToolShape::kCapsule:
      return fmt::format("a capsule, radius {:.3g} mm, shaft {:.3g} mm", 1e3 * t.radius_m, 1e3 * t.length_m);
    case procedures::ToolShape::kMesh:
      return fmt::format("the mesh {}", t.mesh);
  }
  return "?";
}

}  // namespace

GuiCommands tool_commands(const scene::HofProject& project, const ToolChoice& choice) {
  GuiCommands out;
  using Kind = ToolChoice::Kind;
  if (choice.kind == Kind::kNeedle) {
    out.push_back(action::MountNeedle{true});
    return out;
  }
  if (choice.kind == Kind::kPoint) {
    if (project.needle) out.push_back(action::MountNeedle{false});
    if (project.tool) out.push_back(action::EditProject{scene::project_edit::Tool{std::nullopt}, {"haptics/tool off"}});
    return out;
  }
  // The project's own tool settings carry over (its orientation on the stylus, its coupling).
  procedures::ShapedToolConfig tool = project.tool.value_or(procedures::ShapedToolConfig{});
  tool.shape = choice.kind == Kind::kSphere    ? procedures::ToolShape::kSphere
               : choice.kind == Kind::kCapsule ? procedures::ToolShape::kCapsule
                                               : procedures::ToolShape::kMesh;
  tool.radius_m = choice.radius_m;
  if (choice.kind == Kind::kCapsule) tool.length_m = choice.length_m;
  tool.mesh = choice.kind == Kind::kMesh ? choice.mesh : std::string();
  std::string setting =
      fmt::format("haptics/tool {} radius={}", procedures::shape_name(tool.shape), number_text(tool.radius_m));
  if (choice.kind == Kind::kCapsule) setting += " length=" + number_text(tool.length_m);
  if (choice.kind == Kind::kMesh) setting += " mesh=" + tool.mesh;
  out.push_back(action::EditProject{scene::project_edit::Tool{tool}, {setting}});
  return out;
}

GuiCommands tool_panel(const WorldView& w, ToolPanelState& ui) {
  GuiCommands out;
  if (!ui.synced) {
    // The inputs start from what the project mounts.
    ui.kind = static_cast<int>(mounted(w.project));
    if (w.project.tool) {
      ui.radius_mm = static_cast<float>(1e3 * w.project.tool->radius_m);
      ui.length_mm = static_cast<float>(1e3 * w.project.tool->length_m);
      ui.mesh.fill('\0');
      std::strncpy(ui.mesh.data(), w.project.tool->mesh.c_str(), ui.mesh.size() - 1);
    }
    ui.synced = true;
  }
  ImGui::TextWrapped("On the stylus: %s", described(w.project).c_str());
  for (int k = 0; k < 5; ++k) {
    if (k > 0) ImGui::SameLine();
    ImGui::RadioButton(kKindNames[k], &ui.kind, k);
  }
  const auto kind = static_cast<ToolChoice::Kind>(ui.kind);
  using Kind = ToolChoice::Kind;
  if (kind == Kind::kSphere || kind == Kind::kCapsule || kind == Kind::kMesh) {
    ImGui::SetNextItemWidth(110);
    ImGui::InputFloat(kind == Kind::kMesh ? "sphere radius (mm, 0: auto)" : "radius (mm)", &ui.radius_mm, 0.0f, 0.0f,
                      "%.3g");
  }
  if (kind == Kind::kCapsule) {
    ImGui::SetNextItemWidth(110);
    ImGui::InputFloat("shaft length (mm)", &ui.length_mm, 0.0f, 0.0f, "%.3g");
  }
  if (kind == Kind::kMesh) {
    ImGui::SetNextItemWidth(260);
    ImGui::InputText("OBJ/STL file", ui.mesh.data(), ui.mesh.size());
    ImGui::TextDisabled("closed, in the tool's frame: tip at the origin, shaft along +z");
  }
  if (kind == Kind::kNeedle) ImGui::TextDisabled("the needle of the project (its tissues: the Needle panel)");
  const bool same = kind == mounted(w.project) && (kind == Kind::kPoint || kind == Kind::kNeedle);
  if (ImGui::Button("Mount on the stylus") && !same) {
    ToolChoice choice;
    choice.kind = kind;
    choice.radius_m = 1e-3 * static_cast<double>(ui.radius_mm);
    choice.length_m = 1e-3 * static_cast<double>(ui.length_mm);
    choice.mesh = ui.mesh.data();
    out = tool_commands(w.project, choice);
    ui.synced = false;
  }
  if (w.tool && w.mouse_stylus) ImGui::TextWrapped("Turn it: Alt + left drag, or the arrow keys; R turns it back.");
  return out;
}

}  // namespace hof::app::gui
