#pragma once
/// @file
/// What a run of a session records and reports, shared by `hof run` and the Python module
/// (`world.run()`), so that both give the same telemetry and the same summary.json from the
/// same samples: the telemetry rows (telemetry.csv's columns), the presses (palpation), the
/// needle's phases, the summary, and the report folder's other files (a .vtu per deformable
/// body, the plots).

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/press_recorder.h"
#include "hof/coupling/session.h"
#include "hof/scene/world.h"

namespace hof::app {

/// One row of telemetry.csv: a haptic tick that had a device reading.
struct TelemetryRow {
  double time_s{0.0};
  Vec3 device{Vec3::Zero()}, proxy{Vec3::Zero()}, force{Vec3::Zero()};  ///< m, m, N (world frame)
  bool contact{false};
  double penetration_m{0.0};
  double period_s{0.0};
  double indentation_m{0.0};  ///< the tissue's inward motion at the contact since the press began
  std::int32_t body{-1};      ///< the body touched (index), -1: none
  std::int32_t press{0};      ///< the press the tick belongs to (1, 2, ...; 0 between presses)
  // With a needle mounted:
  double needle_depth_m{0.0};
  std::int32_t needle_phase{0};    ///< procedures::NeedlePhase
  double needle_force_n{0.0};      ///< the model's force along the needle
  double sent_axial_force_n{0.0};  ///< the force sent to the device, along the needle
};

/// How a run went beyond what the session reports (for summary.json).
struct RunConditions {
  bool deterministic{true};
  bool memory_locked{false};
  int cpus_kept_awake{0};
  std::string keep_awake{"off (virtual time)"};
  std::optional<double> host_cpu_steal_s;
  std::string telemetry_problem;
  std::string stopped_by;  ///< "SIGINT", "SIGTERM": the run was stopped before its end
};

/// The run length `hof run` takes when none is given: 5 s, or a scripted motion's whole length
/// (and half a second more) when it is longer, up to an hour.
[[nodiscard]] double default_run_seconds(const coupling::Session& session);

/// Records the samples of one run of `session` (built from `world`: its bodies may have been
/// moved into the session; the rest is read). Keep both alive while it is used.
class RunRecording {
 public:
  /// `telemetry_rate_hz`: rows per second of simulated time, 0 = every tick with a reading.
  RunRecording(const coupling::Session& session, const scene::World& world, double telemetry_rate_hz = 0.0);
  ~RunRecording();
  RunRecording(const RunRecording&) = delete;
  RunRecording& operator=(const RunRecording&) = delete;

  /// Takes one haptic sample. Returns its telemetry row, or null when it makes none (no
  /// reading: a script that has ended, a device gone; between rows at a reduced rate). The row
  /// stays valid until the next call.
  const TelemetryRow* add(const haptics::HapticSample& sample);

  [[nodiscard]] bool needle_mounted() const;
  /// The CSV header line (with its newline) and one row's line, as telemetry.csv holds them.
  [[nodiscard]] std::string csv_header() const;
  [[nodiscard]] std::string csv_row(const TelemetryRow& row) const;
  /// The telemetry column names, in the CSV's order.
  [[nodiscard]] std::vector<std::string> column_names() const;
  /// The names of the bodies, as the `body` column writes them (CSV-quoted where needed).
  [[nodiscard]] const std::vector<std::string>& body_names() const;

  [[nodiscard]] const coupling::PressRecorder& presses() const;
  /// The force limit the safety filter held (N): the device's, or the project's when lower.
  [[nodiscard]] double max_force_n() const;
  /// Share of the contact time spent at the force limit.
  [[nodiscard]] double clamped_share(const coupling::SessionReport& report) const;

  /// summary.json's text (a JSON object, two-space indented, with its final newline).
  [[nodiscard]] std::string summary_json(const coupling::SessionReport& report, const RunConditions& conditions) const;

  /// Writes the report's files other than telemetry.csv and summary.json into `dir`: the
  /// final shape of every deformable body (NAME.vtu) and the plots. Returns false if a file
  /// could not be written (said on stderr; the others are still written).
  bool write_report_files(const std::filesystem::path& dir, const coupling::SessionReport& report, bool quiet) const;

  /// The terminal summary `hof run` prints.
  void print(const coupling::SessionReport& report, bool deterministic,
             const std::optional<std::filesystem::path>& out) const;
  /// The warnings `hof run` prints after the summary (force limit, scheduling, a start inside).
  void print_warnings(const coupling::SessionReport& report, bool deterministic, bool quiet) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hof::app
