// The Touch panel: the contact at the latest tick (body, point, normal, force, indentation),
// or the needle's state (the thesis' field network, live).
#include <fmt/format.h>
#include <imgui.h>

#include "hof/app/gui/detail/panels.h"
#include "hof/app/gui/detail/scene_drawing.h"

namespace hof::app::gui {

GuiCommands touch_panel(const WorldView& w) {
  const double unit = w.length_unit == "m" ? 1.0 : 1e-3;  // telemetry is in scene units for a SOFA scene
  if (w.needle && w.last.tool.active) {
    // The thesis' field network (touched, capsule, broken, distance, force, normal), live.
    const haptics::ToolState& t = w.last.tool;
    const auto phase = static_cast<procedures::NeedlePhase>(t.phase);
    const render::Rgba c = phase_colour(phase);
    ImGui::Text("needle");
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(c.x(), c.y(), c.z(), 1.0f), "%s", std::string(procedures::phase_name(phase)).c_str());
    const double to_shown = 1e3;  // the needle's lengths are SI
    const char* length = "mm";
    const std::string body = t.body >= 0 && static_cast<std::size_t>(t.body) < w.bodies.size()
                                 ? w.bodies[static_cast<std::size_t>(t.body)].name
                                 : "-";
    const double capsule = t.body >= 0 ? w.needle->parameters(static_cast<std::size_t>(t.body)).capsule_m : 0.0;
    ImGui::Text("touched %s, capsule %s, body %s", t.touched ? "yes" : "no",
                !t.touched ? "-"
                : t.broken ? "broken"
                           : fmt::format("intact ({:.1f} {})", to_shown * capsule, length).c_str(),
                body.c_str());
    ImGui::Text("depth %.2f %s, force along the needle %.3f N", to_shown * t.depth_m, length, t.axial_force_n);
    ImGui::Text("sent %.3f N, normal %.2f %.2f %.2f", w.last.force.norm(), t.normal.x(), t.normal.y(), t.normal.z());
    if (t.touched) ImGui::Text("entry  %.4f %.4f %.4f", t.entry.x(), t.entry.y(), t.entry.z());
  } else if (w.tool && w.last.tool.active) {
    // A tool with a shape: what its shape touches (it renders every surface itself).
    const haptics::ToolState& t = w.last.tool;
    ImGui::Text("%s tool: %s", std::string(procedures::shape_name(w.tool->config().shape)).c_str(),
                t.contact_count > 0 ? "touching" : "free");
    if (t.contact_count > 0) {
      ImGui::Text("body %s, %d contact points", w.body_name(t.body, "?").c_str(), t.contact_count);
      ImGui::Text("force  %.3f N  (%.2f %.2f %.2f)", w.last.force.norm(), w.last.force.x(), w.last.force.y(),
                  w.last.force.z());
      ImGui::Text("torque %.4f N·%s about the device point", t.torque.norm(), w.length_unit.c_str());
    } else {
      ImGui::TextDisabled("left-drag onto a body, wheel or W/S to press; Alt + left drag turns it");
    }
  } else if (w.last.contact) {
    const std::string body = w.contact_body >= 0 && static_cast<std::size_t>(w.contact_body) < w.bodies.size()
                                 ? w.bodies[static_cast<std::size_t>(w.contact_body)].name
                                 : "?";
    ImGui::Text("body %s, triangle %d", body.c_str(), w.last.triangle);
    ImGui::Text("point  %.4f %.4f %.4f", w.last.contact_point.x(), w.last.contact_point.y(), w.last.contact_point.z());
    ImGui::Text("normal %.3f %.3f %.3f", w.last.contact_normal.x(), w.last.contact_normal.y(),
                w.last.contact_normal.z());
    ImGui::Text("force  %.3f N  (%.2f %.2f %.2f)", w.last.force.norm(), w.last.force.x(), w.last.force.y(),
                w.last.force.z());
    ImGui::Text("indentation %.2f mm, proxy-device %.2f mm", 1e3 * w.indentation_m * unit,
                1e3 * w.last.penetration_m * unit);
  } else {
    ImGui::TextDisabled("no contact%s", w.mouse_stylus ? " (left-drag onto a body, wheel or W/S to press)" : "");
  }
  return {};
}

}  // namespace hof::app::gui
