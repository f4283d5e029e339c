#pragma once
/// @file
/// `hof gui [FILE]`: the window (GLFW, Dear ImGui, OpenGL 3.3). It is a client of the world:
/// it builds it with scene::build_world, starts the session's haptic and simulation threads,
/// draws the latest snapshots, and changes settings only through the command seam. It never
/// steps the simulation and never holds a lock that the haptic loop could wait on.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "hof/coupling/session.h"
#include "hof/haptics/cpu_keep_awake.h"

namespace hof::app {

/// What a run of the window did, for `hof bench` (the framework with the window open).
struct GuiRunResult {
  std::uint64_t frames{0};
  double wall_s{0.0};                              ///< from the window's first frame to its last
  std::optional<coupling::SessionReport> session;  ///< the world's session, stopped at the end
};

struct GuiOptions {
  std::optional<std::filesystem::path> file;    ///< project, SOFA or X3D scene
  std::string device;                           ///< overrides the project's ("" = its own, or the mouse)
  std::optional<std::filesystem::path> script;  ///< run these actions, then exit
  int width{1280}, height{720};
  bool quiet{false};
  /// Keep the CPUs from halting so the haptic thread wakes on time (cpu_keep_awake.h).
  haptics::KeepAwake keep_awake{haptics::KeepAwake::automatic};
  /// The simulation's threads (0: automatic, every core but one, left to the haptic loop and
  /// the window).
  int simulation_threads{0};
  /// The haptic loop on a CPU of its own, the simulation on the others.
  bool pin_threads{true};
  GuiRunResult* result{nullptr};  ///< filled when the run ends, if given
};

/// Runs the window until it is closed (or the script ends). Returns the exit status: 0, or 1
/// after an error (no display, a script error, a file that does not load under a script).
int run_gui(const GuiOptions& options);

}  // namespace hof::app
