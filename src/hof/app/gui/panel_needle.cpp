// The Needle panel: the needle stylus mounted or taken off, its insertion axis and filter,
// and the tissue parameters (the common set, then each body's own).
#include <fmt/format.h>
#include <imgui.h>

#include <array>
#include <charconv>
#include <functional>
#include <optional>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

namespace {

using Tissue = procedures::TissueNeedleParameters;
/// A change of one tissue set: the file's attribute, the value's text, the change made.
using TissueChange =
    std::function<void(const char* attribute, const std::string& value, const std::function<void(Tissue&)>& apply)>;

/// One tissue set's parameters, each change given to `set`.
void tissue_editor(const Tissue& t, const std::string& label, const TissueChange& set) {
  if (!ImGui::TreeNodeEx(label.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return;
  int model = static_cast<int>(t.model);
  const char* models[] = {"fung", "simone-okamura"};
  ImGui::SetNextItemWidth(150);
  if (ImGui::Combo("model", &model, models, 2))
    set("model", models[model], [&](Tissue& u) { u.model = static_cast<procedures::NeedleForceModel>(model); });
  bool pierceable = t.pierceable;
  if (ImGui::Checkbox("pierceable", &pierceable))
    set("pierceable", pierceable ? "true" : "false", [&](Tissue& u) { u.pierceable = pierceable; });
  const auto number = [&](const char* text, const char* attribute, double Tissue::*field) {
    double value = t.*field;
    ImGui::SetNextItemWidth(150);
    if (ImGui::InputDouble(text, &value, 0.0, 0.0, "%.5g", ImGuiInputTextFlags_EnterReturnsTrue))
      set(attribute, number_text(value), [&](Tissue& u) { u.*field = value; });
  };
  // Three or four numbers; `apply` takes them as the file would read them.
  const auto numbers = [&](const char* text, const char* attribute, std::vector<double> values, const auto& apply) {
    std::array<float, 4> f{};
    for (std::size_t i = 0; i < values.size(); ++i) f[i] = static_cast<float>(values[i]);
    ImGui::SetNextItemWidth(230);
    bool changed = values.size() == 4
                       ? ImGui::InputFloat4(text, f.data(), "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)
                       : ImGui::InputFloat3(text, f.data(), "%.4g", ImGuiInputTextFlags_EnterReturnsTrue);
    if (!changed) return;
    // A float's shortest text (0.01145, not 0.011450000107…), the value the user sees, read
    // back as a double: what the file would hold.
    std::string joined;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const std::string shortest = fmt::format("{}", f[i]);
      joined += (i ? " " : "") + shortest;
      (void)std::from_chars(shortest.data(), shortest.data() + shortest.size(), values[i]);
    }
    set(attribute, joined, [&](Tissue& u) { apply(u, values); });
  };
  number("capsule (m)", "capsule", &Tissue::capsule_m);
  number("punctureForce (N)", "punctureForce", &Tissue::puncture_force_n);
  number("relaxationTime (s)", "relaxationTime", &Tissue::relaxation_time_s);
  if (t.model == procedures::NeedleForceModel::kFung) {
    int form = static_cast<int>(t.fung_form);
    const char* forms[] = {"integrated", "printed"};
    ImGui::SetNextItemWidth(150);
    if (ImGui::Combo("fungForm", &form, forms, 2))
      set("fungForm", forms[form], [&](Tissue& u) { u.fung_form = static_cast<procedures::FungForm>(form); });
    numbers("fungPre a b d0 F0", "fungPre", {t.fung_pre.a_per_m, t.fung_pre.b_n, t.fung_pre.d0_m, t.fung_pre.f0_n},
            [](Tissue& u, const std::vector<double>& v) {
              u.fung_pre = {v[0], v[1], v[2], v[3]};
            });
    numbers("fungPost a b d0 F0", "fungPost",
            {t.fung_post.a_per_m, t.fung_post.b_n, t.fung_post.d0_m, t.fung_post.f0_n},
            [](Tissue& u, const std::vector<double>& v) {
              u.fung_post = {v[0], v[1], v[2], v[3]};
            });
    ImGui::TextDisabled(t.fung_form == procedures::FungForm::kIntegrated
                            ? "f(d) = (F0 + b) exp(a (d - d0)) - b; SI: 1/m, N, m, N"
                            : "f(d) = (F0 + b) exp(a (d - d0)) + b; SI: 1/m, N, m, N");
  } else {
    numbers("stiffness a0 a1 a2", "stiffness", {t.stiffness.a0_n, t.stiffness.a1_n_per_m, t.stiffness.a2_n_per_m2},
            [](Tissue& u, const std::vector<double>& v) {
              u.stiffness = {v[0], v[1], v[2]};
            });
    number("cuttingForce (N)", "cuttingForce", &Tissue::cutting_force_n);
  }
  numbers("friction Cp Cn bp bn", "friction",
          {t.friction.static_positive_n_per_m, t.friction.static_negative_n_per_m,
           t.friction.damping_positive_n_s_per_m2, t.friction.damping_negative_n_s_per_m2},
          [](Tissue& u, const std::vector<double>& v) {
            u.friction.static_positive_n_per_m = v[0];
            u.friction.static_negative_n_per_m = v[1];
            u.friction.damping_positive_n_s_per_m2 = v[2];
            u.friction.damping_negative_n_s_per_m2 = v[3];
          });
  ImGui::SetNextItemWidth(150);
  double band = t.friction.velocity_band_m_per_s;
  if (ImGui::InputDouble("frictionVelocityBand (m/s)", &band, 0.0, 0.0, "%.5g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    set("frictionVelocityBand", number_text(band), [&](Tissue& u) { u.friction.velocity_band_m_per_s = band; });
  }
  number("lateralStiffness (N/m)", "lateralStiffness", &Tissue::lateral_stiffness_n_per_m);
  number("lateralDamping (N s/m)", "lateralDamping", &Tissue::lateral_damping_n_s_per_m);
  number("spreadRadius (m)", "spreadRadius", &Tissue::spread_radius_m);
  number("pathTolerance (m)", "pathTolerance", &Tissue::path_tolerance_m);
  ImGui::TreePop();
}

}  // namespace

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
  // The needle changed this frame, as one typed edit of the project's needle (each change
  // named as the project file names it, for messages and a recording).
  std::optional<action::EditProject> edit;
  const auto change = [&](const std::string& element, const char* attribute, const std::string& value,
                          const auto& apply) {
    if (!edit) edit = action::EditProject{scene::project_edit::Needle{*w.project.needle}, {}};
    apply(std::get<scene::project_edit::Needle>(edit->edit).needle);
    edit->settings.push_back(fmt::format("{}@{} {}", element, attribute, value));
  };
  const procedures::NeedleConfig& n = *w.project.needle;
  int axis = static_cast<int>(n.axis);
  const char* axes[] = {"motion", "normal", "stylus"};
  ImGui::SetNextItemWidth(120);
  if (ImGui::Combo("axis at first contact", &axis, axes, 3)) {
    change("haptics/needle", "axis", axes[axis],
           [&](procedures::NeedleConfig& c) { c.axis = static_cast<procedures::NeedleAxis>(axis); });
  }
  double filter = n.velocity_filter_s;
  ImGui::SetNextItemWidth(120);
  if (ImGui::InputDouble("velocityFilter (s)", &filter, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    change("haptics/needle", "velocityFilter", number_text(filter),
           [&](procedures::NeedleConfig& c) { c.velocity_filter_s = filter; });
  }
  // The common set (every deformable body, k = 0), then each body's own (k ≥ 1): tissue[k + 1]
  // as the file orders them.
  const auto edit_tissue = [&](std::size_t k, const Tissue& t, const std::string& label) {
    const std::string element =
        k == 0 ? std::string("haptics/needle/tissue") : fmt::format("haptics/needle/tissue[{}]", k + 1);
    tissue_editor(t, label,
                  [&](const char* attribute, const std::string& value, const std::function<void(Tissue&)>& apply) {
                    change(element, attribute, value,
                           [&](procedures::NeedleConfig& c) { apply(k == 0 ? c.tissue : c.bodies[k - 1].second); });
                  });
  };
  edit_tissue(0, n.tissue, "tissue of every deformable body");
  for (std::size_t k = 0; k < n.bodies.size(); ++k)
    edit_tissue(k + 1, n.bodies[k].second, "tissue of " + n.bodies[k].first);
  if (edit) out.push_back(std::move(*edit));
  return out;
}

}  // namespace hof::app::gui
