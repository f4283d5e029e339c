// The Needle panel: the needle stylus mounted or taken off, its insertion axis and filter,
// and the tissue parameters (the common set, then each body's own).
#include <fmt/format.h>
#include <imgui.h>

#include <array>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

GuiCommands needle_panel(const WorldView& w) {
  GuiCommands out;
  bool mounted = w.project.needle.has_value();
  if (ImGui::Checkbox("the stylus is a needle (reopens the world)", &mounted)) {
    out.push_back(action::MountNeedle{mounted});
  }
  if (!w.project.needle || !w.needle) {
    ImGui::TextDisabled("insertion with Maurin's or Simone-Okamura's model (docs/needle.md)");
    return out;
  }
  const auto set = [&](const std::string& element, const char* attribute, const std::string& value) {
    out.push_back(action::SetAttribute{element, attribute, value});
  };
  const procedures::NeedleConfig& n = *w.project.needle;
  int axis = static_cast<int>(n.axis);
  const char* axes[] = {"motion", "normal", "stylus"};
  ImGui::SetNextItemWidth(120);
  if (ImGui::Combo("axis at first contact", &axis, axes, 3)) set("haptics/needle", "axis", axes[axis]);
  double filter = n.velocity_filter_s;
  ImGui::SetNextItemWidth(120);
  if (ImGui::InputDouble("velocityFilter (s)", &filter, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    set("haptics/needle", "velocityFilter", number_text(filter));
  }
  // The common set (every deformable body), then each body's own: tissue[k] as the file orders them.
  const auto edit_tissue = [&](const std::string& element, const procedures::TissueNeedleParameters& t,
                               const std::string& label) {
    if (!ImGui::TreeNodeEx(label.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return;
    int model = static_cast<int>(t.model);
    const char* models[] = {"fung", "simone-okamura"};
    ImGui::SetNextItemWidth(150);
    if (ImGui::Combo("model", &model, models, 2)) set(element, "model", models[model]);
    bool pierceable = t.pierceable;
    if (ImGui::Checkbox("pierceable", &pierceable)) set(element, "pierceable", pierceable ? "true" : "false");
    const auto number = [&](const char* text, const char* attribute, double value) {
      ImGui::SetNextItemWidth(150);
      if (ImGui::InputDouble(text, &value, 0.0, 0.0, "%.5g", ImGuiInputTextFlags_EnterReturnsTrue))
        set(element, attribute, number_text(value));
    };
    const auto numbers = [&](const char* text, const char* attribute, std::vector<double> values) {
      std::array<float, 4> f{};
      for (std::size_t i = 0; i < values.size(); ++i) f[i] = static_cast<float>(values[i]);
      ImGui::SetNextItemWidth(230);
      bool changed = values.size() == 4
                         ? ImGui::InputFloat4(text, f.data(), "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)
                         : ImGui::InputFloat3(text, f.data(), "%.4g", ImGuiInputTextFlags_EnterReturnsTrue);
      if (!changed) return;
      std::string joined;
      // A float's shortest text (0.01145, not 0.011450000107…): the values the user sees.
      for (std::size_t i = 0; i < values.size(); ++i) joined += (i ? " " : "") + fmt::format("{}", f[i]);
      set(element, attribute, joined);
    };
    number("capsule (m)", "capsule", t.capsule_m);
    number("punctureForce (N)", "punctureForce", t.puncture_force_n);
    number("relaxationTime (s)", "relaxationTime", t.relaxation_time_s);
    if (t.model == procedures::NeedleForceModel::kFung) {
      int form = static_cast<int>(t.fung_form);
      const char* forms[] = {"integrated", "printed"};
      ImGui::SetNextItemWidth(150);
      if (ImGui::Combo("fungForm", &form, forms, 2)) set(element, "fungForm", forms[form]);
      numbers("fungPre a b d0 F0", "fungPre", {t.fung_pre.a_per_m, t.fung_pre.b_n, t.fung_pre.d0_m, t.fung_pre.f0_n});
      numbers("fungPost a b d0 F0", "fungPost",
              {t.fung_post.a_per_m, t.fung_post.b_n, t.fung_post.d0_m, t.fung_post.f0_n});
      ImGui::TextDisabled(t.fung_form == procedures::FungForm::kIntegrated
                              ? "f(d) = (F0 + b) exp(a (d - d0)) - b; SI: 1/m, N, m, N"
                              : "f(d) = (F0 + b) exp(a (d - d0)) + b; SI: 1/m, N, m, N");
    } else {
      numbers("stiffness a0 a1 a2", "stiffness", {t.stiffness.a0_n, t.stiffness.a1_n_per_m, t.stiffness.a2_n_per_m2});
      number("cuttingForce (N)", "cuttingForce", t.cutting_force_n);
    }
    numbers("friction Cp Cn bp bn", "friction",
            {t.friction.static_positive_n_per_m, t.friction.static_negative_n_per_m,
             t.friction.damping_positive_n_s_per_m2, t.friction.damping_negative_n_s_per_m2});
    number("frictionVelocityBand (m/s)", "frictionVelocityBand", t.friction.velocity_band_m_per_s);
    number("lateralStiffness (N/m)", "lateralStiffness", t.lateral_stiffness_n_per_m);
    number("lateralDamping (N s/m)", "lateralDamping", t.lateral_damping_n_s_per_m);
    number("spreadRadius (m)", "spreadRadius", t.spread_radius_m);
    number("pathTolerance (m)", "pathTolerance", t.path_tolerance_m);
    ImGui::TreePop();
  };
  const procedures::NeedleConfig& current = n;
  edit_tissue("haptics/needle/tissue", current.tissue, "tissue of every deformable body");
  for (std::size_t k = 0; k < current.bodies.size(); ++k) {
    edit_tissue(fmt::format("haptics/needle/tissue[{}]", k + 2), current.bodies[k].second,
                "tissue of " + current.bodies[k].first);
  }
  return out;
}

}  // namespace hof::app::gui
