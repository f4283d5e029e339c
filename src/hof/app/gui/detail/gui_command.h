#pragma once
/// @file
/// What a panel asks of the window: a command to the session (coupling::Command, passed
/// through its seam as it is) or an action of the window (a setting by the project file's
/// names, a scene edit, a region, the needle, recording, the view). A panel returns them; the
/// window applies them, in order, after the panel is drawn.

#include <cstdint>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "hof/coupling/session.h"
#include "hof/haptics/force_effects.h"
#include "hof/scene/project.h"
#include "hof/scene/project_edit.h"
#include "hof/scene/sofa_scene_edit.h"

namespace hof::app::gui {

namespace action {
/// A setting by the project file's own names (mechanics/BODY/COMPONENT@PARAMETER,
/// haptics/surface@stiffness, graphics@renderMode, ...), as `set` in a script.
struct SetAttribute {
  std::string element, attribute, value;
};
/// A typed edit of the project (the device, the calibration, the force limit, the options, the
/// force effects, the needle and its tissues: scene::ProjectEdit), checked by scene::check_edit
/// as the file's reader checks it; `settings` names each change as the project file does
/// ("haptics/safety@maxForce 4"), for messages and a recording's events.
struct EditProject {
  scene::ProjectEdit edit;
  std::vector<std::string> settings;
};
/// The project's graphics settings replaced (a typed edit of HofProject::graphics, checked by
/// scene::check_graphics); `settings` names each change as the project file does
/// ("graphics@renderMode wireframe"), for a recording's events.
struct SetGraphics {
  scene::GraphicsSetup graphics;
  std::vector<std::string> settings;
};
/// The project's haptic surface replaced (HofProject::surface, checked by haptics::validate):
/// the bodies without a surface of their own take it.
struct SetSurface {
  haptics::SurfaceMaterial surface;
  std::vector<std::string> settings;
};
/// The project's haptic rendering settings (<haptics renderer proxyRadius forceShading
/// touchableFace>), as HofProject holds them.
struct Rendering {
  haptics::RendererKind renderer{haptics::RendererKind::kRuspini};
  double proxy_radius_m{0.0025};
  bool force_shading{true};
  collision::TouchableFace touchable_face{collision::TouchableFace::kFront};
};
/// The project's rendering settings replaced (typed), sent to the haptic loop as SetRenderer.
struct SetRendering {
  Rendering rendering;
  std::vector<std::string> settings;
};
/// The scene tree's structural edit of a body's node (the world's models rebuilt from it).
struct EditScene {
  scene::SceneEdit edit;
};
/// A component added to a body's node, its values from the body's current ones.
struct AddComponent {
  enum class Kind : std::uint8_t {
    kTetrahedronFem,  ///< a TetrahedronFEMForceField with the body's E and ν
    kMeshSprings,     ///< a MeshSpringForceField of the same order of stiffness
    kPinNearStylus,   ///< a FixedProjectiveConstraint of the nodes near the stylus
  };
  std::string body;
  Kind kind{Kind::kTetrahedronFem};
  double pin_radius_m{0.0};  ///< kPinNearStylus: 0 = a twentieth of the scene
};
/// A spherical material region at the stylus, stiffer by `modulus_factor` than the body.
struct AddRegionAtStylus {
  std::string body;
  double radius_m{0.0};  ///< 0: a tenth of the scene
  double modulus_factor{4.0};
};
/// A component switched to another type, with the values that carry over (E, ν, masses).
struct SwitchComponent {
  std::string body, component, choice;
};
/// The material regions replaced as a whole.
struct SetRegions {
  std::vector<scene::MaterialRegion> regions;
};
/// The force effects replaced as a whole (an effect added or removed).
struct SetEffects {
  haptics::ForceEffects effects;
};
struct MountNeedle {
  bool on{false};
};
struct SetAnimating {
  bool on{false};
};
/// Bodies back to rest (the loops started again if the simulation had stopped).
struct ResetWorld {};
struct SetRealtimePacing {
  bool on{true};
};
struct StartRecording {
  std::filesystem::path file;
};
struct StopRecording {};
struct ResetCamera {};
struct DismissError {};
/// A message for the user (an error also shows above the panels).
struct Report {
  std::string message;
  bool error{false};
};
}  // namespace action

using GuiCommand =
    std::variant<coupling::Command, action::SetAttribute, action::EditProject, action::SetGraphics, action::SetSurface,
                 action::SetRendering, action::EditScene, action::AddComponent, action::AddRegionAtStylus,
                 action::SwitchComponent, action::SetRegions, action::SetEffects, action::MountNeedle,
                 action::SetAnimating, action::ResetWorld, action::SetRealtimePacing, action::StartRecording,
                 action::StopRecording, action::ResetCamera, action::DismissError, action::Report>;
using GuiCommands = std::vector<GuiCommand>;

}  // namespace hof::app::gui
