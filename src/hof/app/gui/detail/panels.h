#pragma once
/// @file
/// The window's panels (Dear ImGui, immediate mode): each is a function over the read-only
/// world view that draws its widgets and returns what the user asked for as commands; the
/// window applies them after the panel. A panel's own inputs (a text being typed, a radius
/// to use next) are its state, passed in beside the view.

#include <array>
#include <cstdint>
#include <string>

#include "hof/app/gui/detail/gui_command.h"
#include "hof/app/gui/detail/world_view.h"

namespace hof::app::gui {

/// The world's name, an error, the controls (animate, step, reset, record), the live figures
/// and the force and indentation plots.
[[nodiscard]] GuiCommands controls_panel(const WorldView& w);
/// The contact (or the needle's state) at the latest tick.
[[nodiscard]] GuiCommands touch_panel(const WorldView& w);
/// The needle stylus: mounted or not, and its tissue parameters.
[[nodiscard]] GuiCommands needle_panel(const WorldView& w);

struct MechanicsPanelState {
  float region_radius_m{0.0f};  // 0: a tenth of the scene
  float region_factor{4.0f};    // × the force field's modulus
  float pin_radius_m{0.0f};     // 0: a twentieth of the scene
};
/// The scene tree: each body's components with their parameters, switched, added, removed;
/// the material regions.
[[nodiscard]] GuiCommands mechanics_panel(const WorldView& w, MechanicsPanelState& ui);

struct HapticsPanelState {
  std::array<char, 256> device_spec{};  // the device being typed
};
/// The device, the renderer, the calibration, the surface and the force effects.
[[nodiscard]] GuiCommands haptics_panel(const WorldView& w, HapticsPanelState& ui);
/// The project's graphics settings, and the window's debug views (`view`, edited in place).
[[nodiscard]] GuiCommands graphics_panel(const WorldView& w, ViewOptions& view);
/// What the Tool panel and a script's `tool` choose: the stylus's tool.
struct ToolChoice {
  enum class Kind : std::uint8_t { kPoint, kSphere, kCapsule, kMesh, kNeedle };
  Kind kind{Kind::kPoint};
  double radius_m{0.005};  ///< sphere, capsule; mesh: its spheres' (0: automatic)
  double length_m{0.05};   ///< capsule: the shaft
  std::string mesh;        ///< mesh: the OBJ/STL file
};
/// The commands that put `choice` on the stylus in `project` (a shaped tool keeps the
/// project's orientation, stiffness and damping; the point takes off any tool and the needle).
[[nodiscard]] GuiCommands tool_commands(const scene::HofProject& project, const ToolChoice& choice);

struct ToolPanelState {
  bool synced{false};  // the inputs taken from the project (false: again at the next draw)
  int kind{0};         // ToolChoice::Kind
  float radius_mm{5.0f}, length_mm{50.0f};
  std::array<char, 512> mesh{};
};
/// The tool on the stylus: the point/sphere proxy, a sphere, a capsule, a mesh or the needle.
[[nodiscard]] GuiCommands tool_panel(const WorldView& w, ToolPanelState& ui);
/// Contact between bodies: the debug view (`view`, edited in place), the pairs switched off or on.
[[nodiscard]] GuiCommands contacts_panel(const WorldView& w, ViewOptions& view);
/// The log of messages.
[[nodiscard]] GuiCommands messages_panel(const WorldView& w);

/// A number as the project file writes it (the shortest text that reads back the same).
[[nodiscard]] std::string number_text(double v);

}  // namespace hof::app::gui
