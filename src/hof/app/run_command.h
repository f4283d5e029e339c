#pragma once
/// @file
/// `hof run` (a haptic session on a project or SOFA scene, headless, writing a report) and
/// `hof check` (validate a file and print every problem).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hof/haptics/cpu_keep_awake.h"

namespace hof::app {

struct RunOptions {
  std::filesystem::path file;  ///< .hof project or .scn SOFA scene
  bool headless{true};
  bool deterministic{false};                 ///< virtual time, lock-step (reproducible)
  std::optional<double> seconds;             ///< run length (default 5 s)
  std::optional<long> steps;                 ///< or a number of simulation steps
  std::optional<std::string> device;         ///< overrides the project's device
  std::vector<std::string> more_devices;     ///< --device again: the project's next hands' devices, in order
  std::optional<std::string> tool;           ///< a shaped tool on the stylus (scene::parse_tool_spec)
  std::optional<std::filesystem::path> out;  ///< report folder
  double telemetry_rate_hz{0.0};             ///< 0 = every haptic tick
  bool quiet{false};
  /// Real time: keep the CPUs from halting (auto: on a virtual machine; cpu_keep_awake.h).
  haptics::KeepAwake keep_awake{haptics::KeepAwake::automatic};
  /// Real time: the simulation's threads (0: automatic, every core but one).
  int simulation_threads{0};
  /// Real time: the haptic loop on a CPU of its own, the simulation on the others.
  bool pin_threads{true};
};

/// `hof run`'s exit status for a scene that opens but has nothing to touch (no touchable
/// shape, no force effect): distinct from 1 (an error) and from the statuses of a run.
inline constexpr int kExitNothingToTouch = 5;

int run_session(const RunOptions& options);

struct CheckOptions {
  std::filesystem::path file;
};
int run_check(const CheckOptions& options);

}  // namespace hof::app
