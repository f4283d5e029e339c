#pragma once
/// @file
/// The window (internal to app/gui): GLFW + Dear ImGui 1.86 + OpenGL 3.3 (libepoxy). Threads:
/// this one (the window) draws and reads; the session's haptic thread renders forces at
/// 1 kHz; its simulation thread steps the bodies. What crosses: snapshots (triple buffers),
/// telemetry (an SPSC ring), and commands (the session's seam). Nothing here waits on the
/// haptic loop.
///
/// Its parts, one file each: the frame loop and menus (gui_window.cpp), the world opened and
/// saved (world.cpp), the edits applied (world_edits.cpp), what the loops published taken in
/// (world_update.cpp), the mouse stylus (stylus_input.cpp), the 3D scene (scene_drawing.cpp),
/// recording (recording.cpp), the script runner (script_runner.cpp), and the panels
/// (panel_*.cpp), functions over view() that return commands, applied by apply().

#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "hof/app/gui/detail/file_dialog.h"
#include "hof/app/gui/detail/gui_command.h"
#include "hof/app/gui/detail/panels.h"
#include "hof/app/gui/detail/world_view.h"
#include "hof/app/gui/gui_app.h"
#include "hof/app/gui/gui_script.h"
#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/scene/world.h"

struct GLFWwindow;

namespace hof::app::gui {

class GuiWindow {
 public:
  explicit GuiWindow(const GuiOptions& options) : options_(options) {}
  ~GuiWindow() { shut_down(); }
  GuiWindow(const GuiWindow&) = delete;
  GuiWindow& operator=(const GuiWindow&) = delete;

  Expected<void> create_window();
  /// Opens `file` (or, given, the project in memory that lives at `file`).
  Expected<void> open(const std::filesystem::path& file, const scene::HofProject* in_memory = nullptr);
  int run(std::vector<ScriptAction> script, const std::string& script_name);

 private:
  // The window (gui_window.cpp).
  void frame();
  void draw_panels();
  float draw_menu();
  void draw_dialogs();
  void draw_unsaved_prompts();
  void draw_legend();
  /// What the panels read, for this frame.
  [[nodiscard]] WorldView view() const;
  /// The panels' commands, in order; an error is reported and the rest still applied.
  void apply(const GuiCommands& commands);
  Expected<void> apply(const GuiCommand& command);
  void report(const std::string& message, bool error);
  void remember_recent(const std::filesystem::path& file);
  void shut_down();
  // The world (world.cpp).
  void close_session();
  void take_world_shapes(const std::vector<scene::VisualShape>& visuals);
  void take_tool_shape();
  void place_mouse_stylus_in_front();
  void reset_camera();
  void set_animating(bool on);
  void reset_world();
  Expected<void> save(const std::filesystem::path& path);
  /// The project as it would be saved at `path` (scene re-anchored, parameters as <set>).
  scene::HofProject project_for(const std::filesystem::path& path) const;
  /// Mounts (or takes off) the needle: the world is opened again from the project in memory.
  Expected<void> mount_needle(bool on);
  /// The world opened again from `next` (the parameters changed so far go with it; the camera
  /// and the mouse stylus's turn stay): a tool mounted or taken off.
  Expected<void> reopen_with(scene::HofProject next);
  // Edits (world_edits.cpp).
  /// A setting by the project file's names (a script's `set`, a panel's SetAttribute): parsed
  /// into a typed edit at scene/'s edge, then applied.
  Expected<void> apply_set(const std::string& element, const std::string& attribute, const std::string& value);
  /// A typed edit of the project made, with the session's commands that carry it (`name`:
  /// element@attribute, for messages).
  Expected<void> apply_project_edit(const scene::ProjectEdit& edit, const std::string& name);
  Expected<void> set_mechanics_parameter(const std::string& element, const std::string& attribute,
                                         const std::string& value);
  /// A typed parameter command (a panel's, or a script's once named): submitted, kept for a
  /// save (by the scene's names) and a recording. `name` prefixes its errors ("" : none).
  Expected<void> set_parameter(const coupling::command::SetParameter& set, const std::string& name = {});
  Expected<void> set_device(const scene::HofProject& next, const std::string& name);
  /// A structural change (the scene made inline in the project and edited; and/or the material
  /// regions replaced): the world's models are rebuilt from it and swapped in through the seam.
  Expected<void> change_structure(const std::optional<scene::SceneEdit>& edit,
                                  const std::optional<std::vector<scene::MaterialRegion>>& regions);
  /// A component's switch to another type, with the values that carry over (E, ν, masses).
  Expected<void> switch_component(const std::string& body, const std::string& component, const std::string& choice);
  Expected<void> set_effects(const haptics::ForceEffects& effects);
  /// A pair of bodies' contact switched off or on (submitted; kept in the project's <contact>
  /// when it has one, so that a save keeps it).
  Expected<void> set_contact_pair(const coupling::command::SetContactPair& pair);
  /// Another tool on the stylus (a panel's typed edit of the project's <tool>): the world is
  /// opened again with it.
  Expected<void> set_tool(const scene::HofProject& next, const std::vector<std::string>& settings);
  /// A panel's typed edit of the project: checked (scene::check_edit), then applied.
  Expected<void> edit_project(const action::EditProject& edit);
  Expected<void> set_graphics(const action::SetGraphics& edit);
  Expected<void> set_surface(const action::SetSurface& edit);
  Expected<void> set_rendering(const action::SetRendering& edit);
  /// Settings changed by a typed edit: the project has changes; a recording lists them.
  void note_settings(const std::vector<std::string>& settings);
  Expected<void> add_component(const action::AddComponent& add);
  Expected<void> add_region_at_stylus(const action::AddRegionAtStylus& add);
  /// A body's model as the accepted commands leave it (as built, with the values submitted since).
  [[nodiscard]] mechanics::ModelConfig current_config(const BodyView& body) const;
  // What the loops published (world_update.cpp).
  void update_from_loops();
  void take_sample(const haptics::HapticSample& s);
  void upload_layer(LayerView& layer, const haptics::SurfaceSnapshot& s);
  void update_stress();
  // Recording (recording.cpp).
  Expected<void> start_recording(const std::filesystem::path& file);
  Expected<void> stop_recording();
  Expected<void> export_shape(const std::filesystem::path& path);
  // The mouse stylus (stylus_input.cpp).
  std::optional<Vec3> pick(double x_px, double y_px) const;
  void mouse_to(double window_x, double window_y, double depth_m, bool new_plane);
  void set_mouse_target(const Vec3& world);
  /// Turns the mouse stylus (and the tool it carries) by `rotation` (world frame), or back to
  /// the project's orientation (identity).
  void turn_mouse_stylus(const Eigen::Quaterniond& rotation);
  void set_mouse_orientation(const Eigen::Quaterniond& world);
  void handle_input();
  // The 3D scene (scene_drawing.cpp).
  void draw_scene(int width, int height);
  void draw_bodies();
  void draw_debug_views();
  void draw_stylus();
  void draw_needle(double size);
  /// The shaped tool at its pose (sphere, capsule or mesh), the device, the force.
  void draw_tool(double size);
  /// The debug view of contacts: between bodies (points, force arrows) and the tool's.
  void draw_contacts(double size);
  // The script (script_runner.cpp).
  bool step_script(std::vector<ScriptAction>& script, std::size_t& next, const std::string& name, int& status);

  /// The limit the safety filter holds: the device's, or the project's when lower.
  [[nodiscard]] double force_limit_n() const {
    return project_.safety.max_force_n > 0.0 ? std::min(max_force_n_, project_.safety.max_force_n) : max_force_n_;
  }
  [[nodiscard]] double scene_size() const { return std::max((bounds_max_ - bounds_min_).norm(), 1e-6); }
  /// The calibration the haptic loop reads the mouse stylus through right now.
  [[nodiscard]] const haptics::Calibration& mouse_calibration() const {
    return calibration_pending_ ? pending_calibration_ : calibration_;
  }

  GuiOptions options_;
  GLFWwindow* window_{nullptr};
  bool imgui_ready_{false};
  std::unique_ptr<render::GlRenderer> renderer_;  // made once the context exists
  render::OrbitCamera camera_;
  int view_x_{0}, view_w_{1}, view_h_{1};

  // The world on screen.
  std::filesystem::path file_;
  scene::HofProject project_;  // what a save writes (the file's, with the changes made here)
  std::string world_name_, length_unit_{"m"}, device_spec_;
  bool default_probe_{false};
  std::unique_ptr<coupling::Session> session_;
  haptics::MouseDevice* mouse_{nullptr};
  std::shared_ptr<procedures::NeedleTool> needle_;             // the needle stylus, when the project mounts one
  std::shared_ptr<const procedures::ShapedTool> shaped_tool_;  // a tool with a shape, when mounted
  std::optional<render::MeshBuffer> tool_mesh_;                // a mesh tool's surface (tool frame, world units)
  // Contact between bodies: the settings, the pairs off, the last pass's contacts (read from
  // the session's triple buffer, valid until the next acquire).
  coupling::ContactSettings contact_settings_;
  std::set<BodyPair> disabled_pairs_;
  const coupling::BodyContactsView* contacts_{nullptr};
  std::vector<std::int32_t> near_triangles_;                              // scratch of the tool's contact points
  procedures::NeedlePhase needle_phase_{procedures::NeedlePhase::kFree};  // at the last tick
  haptics::Calibration calibration_;
  double max_force_n_{8.0};
  double workspace_radius_m_{0.08};
  std::vector<LayerView> layers_;
  std::vector<BodyView> bodies_;
  std::vector<VisualView> visuals_;
  Vec3 bounds_min_{Vec3::Constant(-0.1)}, bounds_max_{Vec3::Constant(0.1)};
  bool animating_{true};
  bool dirty_{false};
  bool realtime_pacing_{true};

  // Telemetry.
  haptics::HapticSample last_{};
  LiveStats stats_;
  std::vector<float> plot_force_ = std::vector<float>(kPlotPoints, 0.0f);  // the last kPlotSeconds, oldest first
  std::vector<float> plot_indentation_ = std::vector<float>(kPlotPoints, 0.0f);
  double next_plot_time_{0.0};
  double plot_force_sum_n_{0.0};  // |F| summed over the ticks since the last plot point, N
  std::int64_t plot_force_ticks_{0};
  bool was_in_contact_{false};
  double displaced_at_contact_{0.0};
  double indentation_m_{0.0};
  double max_force_seen_n_{0.0};
  bool reading_{false};  // the device's latest tick had a reading
  double max_displacement_seen_m_{0.0};
  std::uint64_t contact_ticks_{0};
  std::int32_t contact_body_{-1};

  // Mouse stylus.
  Vec3 plane_point_{Vec3::Zero()};
  Vec3 mouse_world_{Vec3::Zero()};
  double mouse_depth_m_{0.0};
  bool dragging_stylus_{false};
  bool turning_stylus_{false};
  Eigen::Quaterniond mouse_orientation_{Eigen::Quaterniond::Identity()};  // world frame
  double last_x_{0.0}, last_y_{0.0};

  ViewOptions view_options_;
  std::set<std::string> warned_;  // warnings already shown for this world
  // Parameter changes submitted since the last structural change (some may still be queued).
  std::vector<scene::ParameterChange> submitted_changes_;
  // A calibration change on its way to the haptic loop: the mouse keeps the old mapping until
  // the session has applied as many as were submitted.
  std::uint64_t calibrations_submitted_{0};
  bool calibration_pending_{false};
  haptics::Calibration pending_calibration_;
  Clock::time_point next_stress_{};
  // The panels' own inputs.
  MechanicsPanelState mechanics_panel_;
  HapticsPanelState haptics_panel_;
  ToolPanelState tool_panel_;

  // Messages and dialogs.
  std::string error_;
  std::deque<std::string> log_;
  FileDialog dialog_;
  bool want_open_dialog_{false}, want_save_dialog_{false}, want_export_dialog_{false}, want_screenshot_dialog_{false};
  bool confirm_quit_{false};
  bool quit_{false};
  std::optional<std::filesystem::path> pending_screenshot_;
  std::vector<std::filesystem::path> recent_;
  std::optional<std::filesystem::path> dropped_;
  std::optional<std::filesystem::path> pending_open_;
  std::optional<Recording> recording_;
  bool want_replay_dialog_{false};  // waits for the user's answer about unsaved changes
  Clock::time_point script_wait_until_{};
  bool script_waiting_{false};
  std::optional<std::string> open_panel_;  // a panel a script opened (taken by the next frame)
};

}  // namespace hof::app::gui
