// The Mechanics panel: the scene tree of each deformable body (its components, their
// parameters, a switch to another type, a component added or removed) and its material regions.
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <optional>

#include "hof/app/gui/detail/component_switch.h"
#include "hof/app/gui/detail/panels.h"
#include "hof/scene/model_parameters.h"

namespace hof::app::gui {

namespace {

/// Below a body's components: add one (a force field, the nodes near the stylus pinned), and
/// the body's material regions.
void structure_editor(const WorldView& w, const BodyView& b, MechanicsPanelState& ui, GuiCommands& out) {
  if (!b.structure) return;
  const std::string id = b.name;
  // Add a component.
  ImGui::SetNextItemWidth(200);
  if (ImGui::BeginCombo(fmt::format("add##{}", id).c_str(), "add a component...")) {
    using Kind = action::AddComponent::Kind;
    if (ImGui::Selectable("TetrahedronFEMForceField"))
      out.push_back(action::AddComponent{b.name, Kind::kTetrahedronFem, 0.0});
    if (ImGui::Selectable("MeshSpringForceField")) out.push_back(action::AddComponent{b.name, Kind::kMeshSprings, 0.0});
    const bool at_stylus = w.last.valid;
    if (ImGui::Selectable("FixedProjectiveConstraint: the nodes near the stylus", false,
                          at_stylus ? 0 : ImGuiSelectableFlags_Disabled)) {
      out.push_back(action::AddComponent{b.name, Kind::kPinNearStylus, ui.pin_radius_m});
    }
    ImGui::EndCombo();
  }
  ImGui::SetNextItemWidth(120);
  ImGui::InputFloat(fmt::format("pin radius (0: auto)##{}", id).c_str(), &ui.pin_radius_m, 0.0f, 0.0f, "%.4g");

  // Material regions.
  ImGui::TextDisabled("tissue regions (elements whose centroid is inside, or a Gmsh physical group)");
  std::optional<std::vector<scene::MaterialRegion>> regions;
  for (std::size_t i = 0; i < w.project.regions.size(); ++i) {
    const scene::MaterialRegion& r = w.project.regions[i];
    if (r.body != b.name) continue;
    std::string material;
    if (r.young_modulus_pa) material += fmt::format(" E = {:.4g} Pa", *r.young_modulus_pa);
    if (r.poisson_ratio) material += fmt::format(" nu = {:.3g}", *r.poisson_ratio);
    if (r.mass_density_kg_per_m3) material += fmt::format(" rho = {:.4g}", *r.mass_density_kg_per_m3);
    const std::string where =
        r.shape == scene::MaterialRegion::Shape::kSphere ? fmt::format("sphere r {:.3g}", r.radius)
        : r.shape == scene::MaterialRegion::Shape::kBox  ? std::string("box")
                                                         : fmt::format("group {}", r.physical_group);
    ImGui::BulletText("%s: %s,%s", r.name.c_str(), where.c_str(), material.c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton(fmt::format("remove##region{}", i).c_str())) {
      regions = w.project.regions;
      regions->erase(regions->begin() + static_cast<std::ptrdiff_t>(i));
    }
  }
  ImGui::SetNextItemWidth(90);
  ImGui::InputFloat(fmt::format("radius##{}", id).c_str(), &ui.region_radius_m, 0.0f, 0.0f, "%.4g");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(70);
  ImGui::InputFloat(fmt::format("x E##{}", id).c_str(), &ui.region_factor, 0.0f, 0.0f, "%.3g");
  const bool has_tets = std::any_of(
      b.structure->force_fields.begin(), b.structure->force_fields.end(),
      [](const auto& f) { return f.tetrahedron_fem || f.neo_hookean || f.triangle_fem || f.hexahedron_fem; });
  if (!has_tets) ImGui::TextDisabled("(regions need an FEM force field)");
  if (has_tets && ImGui::Button(fmt::format("+ region at the stylus##{}", id).c_str())) {
    out.push_back(action::AddRegionAtStylus{b.name, ui.region_radius_m, ui.region_factor});
  }
  if (regions) out.push_back(action::SetRegions{std::move(*regions)});
}

}  // namespace

GuiCommands mechanics_panel(const WorldView& w, MechanicsPanelState& ui) {
  GuiCommands out;
  ImGui::TextDisabled("Enter applies a value (validated; saved with the project)");
  for (const BodyView& b : w.bodies) {
    const std::string label = fmt::format("{} ({})", b.name, b.deformable ? "deformable" : "rigid");
    if (!ImGui::TreeNodeEx(label.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) continue;
    if (!b.structure) {
      ImGui::TextDisabled("fixed shape: touchable, never deforms");
      ImGui::TreePop();
      continue;
    }
    ImGui::TextDisabled("%zu nodes, %zu tetrahedra, %zu fixed", b.structure->positions.size(), b.structure->tets.size(),
                        b.fixed_points.size());
    for (const auto& [component, type] : components_of(*b.structure)) {
      const std::string prefix = component + "/";
      const bool has_parameters = std::any_of(b.parameters.begin(), b.parameters.end(),
                                              [&](const std::string& p) { return p.starts_with(prefix); });
      const std::string node =
          fmt::format("{} {}##{}/{}", type, component.empty() ? b.name : component, b.name, component);
      // The force fields (what is tuned most) start open.
      const bool force_field = type.find("ForceField") != std::string::npos;
      const ImGuiTreeNodeFlags flags = !has_parameters ? ImGuiTreeNodeFlags_Leaf
                                       : force_field   ? ImGuiTreeNodeFlags_DefaultOpen
                                                       : ImGuiTreeNodeFlags_None;
      // Interactive: components can be opened (to switch or remove them) even without parameters.
      const bool editable = !component.empty();
      if (!ImGui::TreeNodeEx(node.c_str(), editable ? (flags & ~ImGuiTreeNodeFlags_Leaf) : flags)) continue;
      if (editable) {
        const std::vector<std::string>* choices =
            type.find("Solver") != std::string::npos && type != "CGLinearSolver" && type != "SparseLDLSolver"
                ? &kOdeSolvers
            : type == "CGLinearSolver" || type == "SparseLDLSolver"                        ? &kLinearSolvers
            : type.find("Mass") != std::string::npos                                       ? &kMasses
            : type.find("ForceField") != std::string::npos && type != "ConstantForceField" ? &kForceFields
                                                                                           : nullptr;
        if (choices) {
          ImGui::SetNextItemWidth(200);
          const std::string combo = fmt::format("type##{}/{}", b.name, component);
          if (ImGui::BeginCombo(combo.c_str(), "switch to...")) {
            for (const std::string& choice : *choices) {
              if (ImGui::Selectable(choice.c_str())) {
                out.push_back(action::SwitchComponent{b.name, component, choice});
              }
            }
            ImGui::EndCombo();
          }
        }
        const bool removable =
            type.find("ForceField") != std::string::npos || type.find("Constraint") != std::string::npos;
        if (removable) {
          if (choices) ImGui::SameLine();
          const std::string remove = fmt::format("remove##{}/{}", b.name, component);
          if (ImGui::SmallButton(remove.c_str())) {
            out.push_back(
                action::EditScene{scene::SceneEdit{scene::SceneEdit::Action::kRemove, b.name, component, "", {}}});
          }
        }
      }
      for (const std::string& p : b.parameters) {
        if (!p.starts_with(prefix)) continue;
        const std::string parameter = p.substr(prefix.size());
        // The value as the accepted commands leave it: the session's.
        const auto ref = scene::resolve_parameter(*b.structure, component, parameter);
        const auto body = scene::body_id(*w.session, b.name);
        if (!ref || !body) continue;
        const auto value = w.session->parameter(*body, *ref);
        if (!value) continue;
        double v = *value;
        ImGui::SetNextItemWidth(130);
        const std::string id = fmt::format("{}##{}/{}", parameter, b.name, p);
        // A typed command: the parameter was resolved above, once (the window names it for a
        // saved project and a recording).
        if (ImGui::InputDouble(id.c_str(), &v, 0.0, 0.0, "%.6g", ImGuiInputTextFlags_EnterReturnsTrue))
          out.push_back(coupling::Command{coupling::command::SetParameter{*body, *ref, v}});
      }
      ImGui::TreePop();
    }
    structure_editor(w, b, ui, out);
    ImGui::TreePop();
  }
  return out;
}

}  // namespace hof::app::gui
