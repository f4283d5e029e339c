// The Contacts panel: contact between bodies as the last pass left it (each pair's contacts
// and force), each pair switched off or on live (command::SetContactPair), and the debug view
// that draws the contacts and the shaped tool's contact points.
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <utility>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

GuiCommands contacts_panel(const WorldView& w, ViewOptions& view) {
  GuiCommands out;
  const coupling::ContactSettings& s = w.contact_settings;
  ImGui::Checkbox("draw contacts (points, force arrows)", &view.show_contacts);
  if (view.show_contacts) {
    ImGui::SetNextItemWidth(160);
    ImGui::SliderFloat("arrow length (x auto)", &view.contact_arrow_scale, 0.1f, 10.0f, "%.2g",
                       ImGuiSliderFlags_Logarithmic);
  }
  if (!s.enabled) {
    ImGui::TextDisabled("bodies do not touch each other in this scene");
    ImGui::TextDisabled("(a .hof <contact>, or a SOFA collision pipeline, turns it on)");
    if (w.tool) ImGui::TextDisabled("the tool's contact points are drawn");
    return out;
  }
  // Lengths as the scene gives them (mm for a scene in metres).
  const bool metres = w.length_unit == "m";
  const double shown = metres ? 1e3 : 1.0;
  const char* unit = metres ? "mm" : w.length_unit.c_str();
  ImGui::TextDisabled("response: %s",
                      s.response == coupling::ContactResponse::kPenalty ? "penalty springs" : "friction constraints");
  ImGui::TextDisabled("kept %.3g %s apart, detected within %.3g %s", shown * s.contact_distance_m, unit,
                      shown * s.alarm_distance_m, unit);
  // Each pair's contacts and total force at the last pass.
  double largest = 0.0;
  const auto pair_figures = [&](std::int32_t a, std::int32_t b) {
    std::size_t count = 0;
    Vec3 on_a = Vec3::Zero();
    if (!w.contacts) return std::pair{count, on_a};
    for (const coupling::BodyContactView& c : w.contacts->contacts) {
      if (c.body_a == a && c.body_b == b) {
        ++count;
        on_a += c.force_on_a_n;
      } else if (c.body_a == b && c.body_b == a) {
        ++count;
        on_a -= c.force_on_a_n;
      }
    }
    return std::pair{count, on_a};
  };
  if (w.contacts) {
    for (const coupling::BodyContactView& c : w.contacts->contacts) largest = std::max(largest, c.force_on_a_n.norm());
    ImGui::Text("last pass: %zu contacts, largest force %.3g N", w.contacts->contacts.size(), largest);
  }
  ImGui::TextDisabled("pairs (unticked: they pass through each other)");
  const auto n = static_cast<std::int32_t>(w.bodies.size());
  for (std::int32_t a = 0; a < n; ++a) {
    const BodyView& ba = w.bodies[static_cast<std::size_t>(a)];
    if (!ba.collides) continue;
    for (std::int32_t b = a + 1; b < n; ++b) {
      const BodyView& bb = w.bodies[static_cast<std::size_t>(b)];
      // Pairs that never touch: a body without collision models, two fixed shapes, one group.
      if (!bb.collides || (!ba.deformable && !bb.deformable) || (ba.group >= 0 && ba.group == bb.group)) continue;
      bool on = !w.disabled_pairs.contains(BodyPair{a, b});
      const auto [count, force] = pair_figures(a, b);
      const std::string label = fmt::format("{} - {}##pair{}-{}", ba.name, bb.name, a, b);
      if (ImGui::Checkbox(label.c_str(), &on)) {
        out.push_back(coupling::Command{
            coupling::command::SetContactPair{static_cast<coupling::BodyId>(a), static_cast<coupling::BodyId>(b), on}});
      }
      ImGui::SameLine();
      ImGui::TextDisabled("%zu contacts, %.3g N", count, force.norm());
    }
  }
  return out;
}

}  // namespace hof::app::gui
