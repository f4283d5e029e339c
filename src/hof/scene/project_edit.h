#pragma once
/// @file
/// A change of a project's haptics or graphics setting as a typed edit: the text a user gives
/// (the file's own names: "haptics/surface", "stiffness", "0.4") is parsed once, here, with
/// the checks the file's reader applies; what comes out is the new value of what the setting
/// belongs to, applied to the project in memory and carried to a running session as typed
/// commands (scene/world.h live_commands). No XML on the way: the file is written only when
/// the project is saved.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "hof/core/error.h"
#include "hof/scene/project.h"

namespace hof::scene {

namespace project_edit {
struct Device {  ///< haptics@device
  std::string spec;
};
struct HapticRate {  ///< haptics@hapticRate (taken when the project is opened again)
  double hz{};
};
struct Rendering {  ///< haptics@renderer, proxyRadius, forceShading, touchableFace
  haptics::RendererKind renderer{};
  double proxy_radius_m{};
  bool force_shading{};
  collision::TouchableFace touchable_face{};
};
struct Coupling {  ///< haptics@coupling (taken when the project is opened again)
  coupling::ContactCoupling coupling{};
};
struct Calibration {  ///< haptics/calibration@positionCalibration, row-major 4x4
  std::array<double, 16> position{};
};
struct Surface {  ///< haptics/surface: the project's surface
  haptics::SurfaceMaterial surface;
};
struct ForceLimit {  ///< haptics/safety@maxForce, N (0: the device's own limit)
  double max_force_n{};
};
struct Safety {  ///< haptics/safety's other settings (taken when the project is opened again)
  haptics::SafetyConfig safety;
};
struct BoundTree {  ///< haptics/options (taken when the project is opened again)
  bool use_bound_tree{};
  int max_triangles_in_leaf{};
};
struct Stylus {  ///< haptics/stylus: the drawn stylus
  double radius_m{};
  double length_m{};
};
struct Needle {  ///< haptics/needle and its tissue sets
  procedures::NeedleConfig needle;
};
struct Tool {  ///< haptics/tool: the shaped tool on the stylus (nullopt: none, the point/sphere proxy)
  std::optional<procedures::ShapedToolConfig> tool;
};
struct Effects {  ///< haptics/effects/…: the force effects as a whole
  haptics::ForceEffects effects;
};
struct Graphics {  ///< graphics and graphics/material, graphics/light: drawn by the window
  GraphicsSetup graphics;
};
}  // namespace project_edit

using ProjectEdit =
    std::variant<project_edit::Device, project_edit::HapticRate, project_edit::Rendering, project_edit::Coupling,
                 project_edit::Calibration, project_edit::Surface, project_edit::ForceLimit, project_edit::Safety,
                 project_edit::BoundTree, project_edit::Stylus, project_edit::Needle, project_edit::Effects,
                 project_edit::Graphics, project_edit::Tool>;

/// The edit that sets `attribute` of `element` to `value` in `project`, by the file's names
/// (set_project_attribute lists them). Errors as the reader's, each naming element@attribute:
/// an element or attribute not known lists the known ones; a value refused says what is
/// allowed (its error carries `path` as the file, as a file's does).
[[nodiscard]] Expected<ProjectEdit> parse_project_edit(const HofProject& project, const std::filesystem::path& path,
                                                       std::string_view element, std::string_view attribute,
                                                       std::string_view value);

/// Checks an edit made in memory (a panel's, not parsed from text) as the file's reader checks
/// what it reads: each changed element's attributes by the reader's table, then the checks of
/// the whole element (a surface, a tissue set, the needle, the haptic rate). The error
/// (kInvalidArgument) is the reader's wording; nothing is changed.
[[nodiscard]] Expected<void> check_edit(const HofProject& project, const ProjectEdit& edit);

/// `edit` made in `project` (checked already: parse_project_edit or check_edit). A tool
/// mounted (project_edit::Tool with a shape) takes the needle's place, as scene::mount_tool.
void apply_edit(HofProject& project, const ProjectEdit& edit);

}  // namespace hof::scene
