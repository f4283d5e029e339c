#include "hof/app/run_command.h"

#include <fmt/format.h>

#include <signal.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>
#include <vector>

#include "hof/app/detail/cli_failure.h"
#include "hof/app/session_recording.h"
#include "hof/core/file_write.h"
#include "hof/core/progress.h"
#include "hof/core/text.h"
#include "hof/coupling/press_recorder.h"
#include "hof/coupling/session.h"
#include "hof/haptics/cpu_keep_awake.h"
#include "hof/haptics/device.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh_io.h"
#include "hof/procedures/needle.h"
#include "hof/scene/device_config.h"
#include "hof/scene/project.h"
#include "hof/scene/world.h"

namespace hof::app {

namespace {

using detail::fail;

// Ticks whose period exceeded `limit_s` (a missed haptic deadline), from the 1 µs histogram.
// CPU time the hypervisor gave to other guests while this machine's CPUs wanted to run (the
// "steal" column of /proc/stat, all CPUs, in seconds). On a virtual machine a haptic deadline
// missed by milliseconds is most often this, which no scheduling inside the guest can prevent.
std::optional<double> host_cpu_steal_s() {
  std::ifstream stat("/proc/stat");
  std::string cpu;
  std::array<double, 8> ticks{};  // user nice system idle iowait irq softirq steal
  if (!(stat >> cpu) || cpu != "cpu") return std::nullopt;
  for (double& t : ticks) {
    if (!(stat >> t)) return std::nullopt;
  }
  const long per_s = ::sysconf(_SC_CLK_TCK);
  return per_s > 0 ? std::optional<double>(ticks[7] / static_cast<double>(per_s)) : std::nullopt;
}

// Closes the telemetry stream and makes sure the rows written during the run are on disk
// under the report folder. If the folder (or the file) was removed while the session ran, the
// rows still live in the open, unlinked file: the folder is made again and they are copied
// out of it. Returns a problem to report ("" when the file is whole).
std::string finish_telemetry(std::FILE* telemetry, const std::filesystem::path& dir) {
  std::string problem;
  if (std::fflush(telemetry) != 0 || std::ferror(telemetry)) {
    problem = fmt::format("telemetry.csv is incomplete: {}", std::strerror(errno));
  }
  struct stat info {};
  const int fd = ::fileno(telemetry);
  if (::fstat(fd, &info) == 0 && info.st_nlink == 0) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    std::string rows;
    std::array<char, 1 << 16> buffer{};
    ssize_t n = 0;
    off_t offset = 0;
    while ((n = ::pread(fd, buffer.data(), buffer.size(), offset)) > 0) {
      rows.append(buffer.data(), static_cast<std::size_t>(n));
      offset += n;
    }
    if (auto written = write_file_atomically(dir / "telemetry.csv", rows); !written) {
      problem =
          fmt::format("the report folder was removed during the run and telemetry.csv could not be written again: {}",
                      written.error().to_string());
    } else if (problem.empty()) {
      problem = "the report folder was removed during the run: it was made again, with the whole telemetry";
    }
  }
  if (std::fclose(telemetry) != 0 && problem.empty()) {
    problem = fmt::format("telemetry.csv is incomplete: {}", std::strerror(errno));
  }
  return problem;
}

// Ctrl-C (SIGINT) and SIGTERM during a run: the handler only stores to lock-free atomics (all a
// signal handler may do); the run ends after its current step and its whole report is written.
std::atomic<coupling::Session*> g_running_session{nullptr};
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void stop_run_on_signal(int signal_number) {
  g_stop_signal = signal_number;
  if (coupling::Session* session = g_running_session.load()) session->request_stop();
}

// Installs the handler for the life of one run and puts the previous handlers back after it,
// so that a second Ctrl-C while the report is written ends the program as usual.
class StopOnSignals {
 public:
  explicit StopOnSignals(coupling::Session& session) {
    g_stop_signal = 0;
    g_running_session.store(&session);
    struct sigaction action {};
    action.sa_handler = stop_run_on_signal;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, &previous_int_);
    ::sigaction(SIGTERM, &action, &previous_term_);
  }
  ~StopOnSignals() {
    ::sigaction(SIGINT, &previous_int_, nullptr);
    ::sigaction(SIGTERM, &previous_term_, nullptr);
    g_running_session.store(nullptr);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

 private:
  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
};

// A numeric option out of its range, in a sentence ("" when all are in range).
std::string numeric_option_problem(const RunOptions& options) {
  if (options.seconds && !(*options.seconds > 0.0 && *options.seconds <= 86400.0)) {
    return fmt::format("--seconds must be in (0, 86400], got {}", *options.seconds);
  }
  if (options.steps && !(*options.steps > 0 && *options.steps <= 100000000)) {
    return fmt::format("--steps must be in [1, 100000000], got {}", *options.steps);
  }
  if (!(options.telemetry_rate_hz >= 0.0 && options.telemetry_rate_hz <= 100000.0)) {
    return fmt::format("--telemetry-rate must be in [0, 100000] rows/s (0 = every tick), got {}",
                       options.telemetry_rate_hz);
  }
  return {};
}

// Locks every page of the process in memory (true when it did), only where the lock has no
// ceiling (root, or an unlimited RLIMIT_MEMLOCK).
bool lock_memory_without_ceiling() {
  rlimit limit{};
  const bool may_lock =
      ::geteuid() == 0 || (::getrlimit(RLIMIT_MEMLOCK, &limit) == 0 && limit.rlim_cur == RLIM_INFINITY);
  return may_lock && ::mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
}

// Writes the report of a run that has ended (summary first, then the other files, then the
// terminal's) and returns the exit status that says how it ended.
int write_run_report(const RunOptions& options, RunRecording& recording, const coupling::SessionReport& report,
                     const RunConditions& conditions, int stop_signal) {
  int report_status = 0;  // 3 when part of the report could not be written
  if (options.out) {
    // Written first and whole (atomically): whatever happens after, the session's results are
    // on disk. The folder is made again if it was removed during the run. If even that fails
    // (a full disk), the summary goes to the terminal rather than being lost.
    std::error_code ec;
    std::filesystem::create_directories(*options.out, ec);
    const std::string text = recording.summary_json(report, conditions);
    if (auto written = write_file_atomically(*options.out / "summary.json", text); !written) {
      std::fprintf(stderr, "hof: %s\nhof: the session's summary follows, so that its results are not lost:\n%s",
                   written.error().to_string().c_str(), text.c_str());
      return 3;
    }
    const std::string& problem = conditions.telemetry_problem;
    if (!problem.empty()) {
      std::fprintf(stderr, "hof: warning: %s\n", problem.c_str());
      if (problem.find("incomplete") != std::string::npos || problem.find("could not") != std::string::npos)
        report_status = 3;
    }
    if (!recording.write_report_files(*options.out, report, options.quiet)) report_status = 3;
  }
  if (!options.quiet) recording.print(report, options.deterministic, options.out);
  recording.print_warnings(report, options.deterministic, options.quiet);
  // Stopped by a signal: its report is whole; the exit status is the shell's for that signal.
  if (stop_signal) return 128 + stop_signal;
  if (report.diverged) return 2;
  // The device failed: the run ended early (its report is written).
  if (!report.device_failure.empty()) return 4;
  return report_status;
}

}  // namespace

int run_session(const RunOptions& options) {
  // Numeric options first: a clear refusal rather than an endless run or a huge file.
  if (const std::string problem = numeric_option_problem(options); !problem.empty()) return fail(problem);
  auto world = scene::build_world(options.file, options.device.value_or(""));
  if (!world) return fail(world.error());
  if (options.tool) {
    auto tool = scene::parse_tool_spec(*options.tool);
    if (!tool) return fail(tool.error());
    if (auto mounted = scene::mount_tool(*world, *tool); !mounted) return fail(mounted.error());
  }
  // --device given again: the next hands' devices (a project with <tool device=…>), in order.
  if (options.more_devices.size() > world->config.more_hands.size()) {
    return fail(
        fmt::format("--device given {} times but {} has {} hand(s) (one <tool device=...> for each hand "
                    "after the first)",
                    1 + options.more_devices.size(), options.file.string(), 1 + world->config.more_hands.size()));
  }
  for (std::size_t h = 0; h < options.more_devices.size(); ++h) {
    const std::string& spec = options.more_devices[h];
    const bool taken =
        spec == world->device ||
        std::any_of(world->config.more_hands.begin(), world->config.more_hands.begin() + static_cast<std::ptrdiff_t>(h),
                    [&](const auto& other) { return other.device == spec; });
    if (taken) return fail(fmt::format("--device {}: given for two hands (each device carries one tool)", spec));
    world->config.more_hands[h].device = spec;
  }
  if (!world->nothing_to_touch.empty()) {
    // Shown by `hof gui`, but a headless run would render nothing: its own status, one line.
    std::fprintf(stderr, "hof: %s: %s; `hof gui` shows it\n", options.file.c_str(),
                 valid_utf8(world->nothing_to_touch).c_str());
    return kExitNothingToTouch;
  }
  for (const std::string& w : world->warnings) {
    if (!options.quiet) std::fprintf(stderr, "hof: warning: %s\n", valid_utf8(w).c_str());
  }
  // (The components not simulated are in the reader's warnings above, and in summary.json.)
  auto device = scene::open_device(world->device);
  if (!device) {
    Error e = device.error();
    e.message = options.device ? fmt::format("{} (the device given by --device)", e.message)
                               : fmt::format("{} (device of {})", e.message, options.file.string());
    return fail(e);
  }
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = !options.deterministic;
  config.simulation_threads = options.simulation_threads;
  config.pin_threads = options.pin_threads;
  // The project's other hands (<tool device=…>), each on its own device.
  std::vector<std::unique_ptr<haptics::Device>> more_devices;
  for (coupling::HandConfig& hand : config.more_hands) {
    hand.haptics.realtime_priority = config.haptics.realtime_priority;
    auto opened = scene::open_device(hand.device);
    if (!opened) {
      Error e = opened.error();
      e.message = fmt::format("{} (a <tool>'s device in {})", e.message, options.file.string());
      return fail(e);
    }
    more_devices.push_back(std::move(*opened));
  }
  auto made = coupling::Session::make(std::move(world->bodies), std::move(*device), std::move(more_devices), config);
  if (!made) return fail(made.error());
  coupling::Session& session = **made;

  double seconds = options.seconds.value_or(default_run_seconds(session));
  if (options.steps) seconds = static_cast<double>(*options.steps) * session.dt();

  RunRecording recording(session, *world, options.telemetry_rate_hz);
  // Telemetry straight to the report folder.
  std::FILE* telemetry = nullptr;
  if (options.out) {
    std::error_code ec;
    std::filesystem::create_directories(*options.out, ec);
    if (ec)
      return fail(
          Error{ErrorCode::kIo, "cannot create the report folder: " + ec.message(), options.out->string(), 0, -1});
    // Read-write: if the folder is removed mid-run the rows are read back from this stream.
    telemetry = std::fopen((*options.out / "telemetry.csv").c_str(), "w+");
    if (!telemetry) return fail(Error{ErrorCode::kIo, "cannot write telemetry.csv", options.out->string(), 0, -1});
    std::fputs(recording.csv_header().c_str(), telemetry);
  }
  auto on_sample = [&](const haptics::HapticSample& s) {
    const TelemetryRow* row = recording.add(s);
    if (telemetry && row) std::fputs(recording.csv_row(*row).c_str(), telemetry);
  };
  const auto progress = make_terminal_progress(options.quiet);
  // Real time: keep every page of the process in memory, so that the haptic thread never waits
  // for a page to come back from disk (where the system permits it; the report says which).
  // Only where the lock has no ceiling (root, or an unlimited RLIMIT_MEMLOCK): under a finite
  // ceiling MCL_FUTURE would turn the first allocation past it into a failure mid-run.
  RunConditions conditions;
  conditions.deterministic = options.deterministic;
  conditions.memory_locked = !options.deterministic && lock_memory_without_ceiling();
  // Real time on a virtual machine: keep its CPUs from halting (cpu_keep_awake.h says why).
  std::optional<haptics::CpuKeepAwake> keep_awake;
  if (!options.deterministic) keep_awake.emplace(options.keep_awake);
  const std::optional<double> steal_before = host_cpu_steal_s();
  std::optional<StopOnSignals> stop_on_signals(std::in_place, session);
  // A signal that came before the run began (which clears a stop request) is passed on again.
  const ProgressSink progress_or_stop = [&](std::string_view what, double fraction) {
    if (g_stop_signal) session.request_stop();
    if (progress) progress(what, fraction);
  };
  const coupling::SessionReport report = options.deterministic
                                             ? session.run_virtual(seconds, on_sample, progress_or_stop)
                                             : session.run_realtime(seconds, on_sample, progress_or_stop);
  stop_on_signals.reset();
  const int stop_signal = g_stop_signal;
  if (stop_signal) {
    conditions.stopped_by = stop_signal == SIGINT    ? "SIGINT"
                            : stop_signal == SIGTERM ? "SIGTERM"
                                                     : fmt::format("signal {}", stop_signal);
    std::fprintf(stderr, "hof: %s: the run stopped after %.3f s of %.3f s; writing the report of what ran\n",
                 conditions.stopped_by.c_str(), report.simulated_s, seconds);
  }
  // The session has run: from here on nothing may lose its results.
  if (telemetry) conditions.telemetry_problem = finish_telemetry(telemetry, *options.out);
  if (keep_awake) {
    conditions.cpus_kept_awake = keep_awake->spinners();
    conditions.keep_awake = keep_awake->reason();
  }
  if (const std::optional<double> steal_after = host_cpu_steal_s(); steal_before && steal_after) {
    conditions.host_cpu_steal_s = *steal_after - *steal_before;
  }

  return write_run_report(options, recording, report, conditions, stop_signal);
}

int run_check(const CheckOptions& options) {
  const std::string ext = options.file.extension().string();
  if (std::error_code ec; std::filesystem::is_directory(options.file, ec)) {
    return fail(
        Error{ErrorCode::kIo,
              "is a folder; hof check takes one file: a project (.hof), a scene (.scn, .x3d) or a mesh (.msh, .obj, "
              ".stl, .off, .vtu)",
              options.file.string(), 0, -1});
  }
  if (ext == ".hof" || ext == ".scn" || ext == ".x3d") {
    // The same builder as `hof run`: what run would refuse is an error here.
    auto world = scene::build_world(options.file);
    if (!world) return fail(world.error());
    int problems = 0;
    std::printf("%s: %zu bod%s, lengths in %s\n", world->scene_path.c_str(), world->bodies.size(),
                world->bodies.size() == 1 ? "y" : "ies", world->length_unit.c_str());
    std::size_t touchable = 0;
    for (const coupling::SessionBody& b : world->bodies) {
      touchable += b.surface.triangles.empty() ? 0 : 1;
      if (b.deformable()) {
        const std::string elements = b.model->element_summary();
        std::printf("  model '%s': %zu nodes, %s, %zu surface triangles (deformable, dt %g s)\n",
                    valid_utf8(b.name).c_str(), b.model->node_count(), elements.c_str(), b.surface.triangles.size(),
                    b.model->dt_s);
      } else {
        std::printf("  shape '%s': %zu triangles (rigid, fixed)\n", valid_utf8(b.name).c_str(),
                    b.surface.triangles.size());
      }
    }
    std::printf(
        "  %zu touchable, %zu spring / %zu viscosity / %zu constant / %zu magnetic geometry / %zu position function / "
        "%zu time function force effects\n",
        touchable, world->config.effects.springs.size(), world->config.effects.viscosities.size(),
        world->config.effects.constants.size(), world->config.effects.magnets.size(),
        world->config.effects.position_functions.size(), world->config.effects.time_functions.size());
    if (world->project.needle) {
      // Which bodies the needle enters, and with what.
      std::vector<std::string> names;
      std::vector<bool> deformable;
      for (const coupling::SessionBody& b : world->bodies) {
        names.push_back(b.name);
        deformable.push_back(b.deformable());
      }
      const auto sets = procedures::parameters_by_body(*world->project.needle, names, deformable);
      for (std::size_t i = 0; i < sets.size(); ++i) {
        const procedures::TissueNeedleParameters& t = sets[i];
        if (!t.pierceable) {
          std::printf("  needle: '%s' is not entered (a wall for the needle)\n", valid_utf8(names[i]).c_str());
          continue;
        }
        std::printf("  needle: enters '%s': %s model, capsule %g m, puncture force %g N, relaxation %g s\n",
                    valid_utf8(names[i]).c_str(), std::string(procedures::model_name(t.model)).c_str(), t.capsule_m,
                    t.puncture_force_n, t.relaxation_time_s);
      }
    }
    if (const auto& t = world->project.tool) {
      std::printf("  tool: %s, radius %g m%s\n", std::string(procedures::shape_name(t->shape)).c_str(), t->radius_m,
                  t->shape == procedures::ToolShape::kCapsule ? fmt::format(", shaft {} m", t->length_m).c_str() : "");
    }
    for (std::size_t h = 0; h < world->project.hands.size(); ++h) {
      const scene::HandSetup& hand = world->project.hands[h];
      const procedures::ShapedToolConfig& t = hand.tool;
      std::printf("  hand %zu: %s, radius %g m%s, device %s%s\n", h + 2,
                  std::string(procedures::shape_name(t.shape)).c_str(), t.radius_m,
                  t.shape == procedures::ToolShape::kCapsule ? fmt::format(", shaft {} m", t.length_m).c_str() : "",
                  valid_utf8(t.device).c_str(),
                  hand.max_force_n > 0.0 ? fmt::format(", force limit {} N", hand.max_force_n).c_str() : "");
      if (auto device = scene::open_device(world->config.more_hands[h].device); !device) {
        std::printf("%s\n", device.error().to_string().c_str());
        ++problems;
      }
    }
    for (const auto& d : world->defaults) std::printf("default: %s\n", valid_utf8(d).c_str());
    // The components not simulated are named once, in the warnings below; those that need no
    // counterpart (plugins, display, the default loops) are counted.
    if (!world->ignored.empty()) {
      std::map<std::string, int> kinds;
      for (const auto& s : world->ignored) ++kinds[s.substr(0, s.find(' '))];
      std::string list;
      for (const auto& [kind, n] : kinds)
        list += fmt::format("{}{}{}", list.empty() ? "" : ", ", kind, n > 1 ? fmt::format(" x{}", n) : "");
      std::printf("  not needed in HoF: %zu component(s): %s\n", world->ignored.size(), list.c_str());
    }
    for (const auto& w : world->warnings) std::printf("warning: %s\n", valid_utf8(w).c_str());
    if (auto device = scene::open_device(world->device); !device) {
      std::printf("%s\n", device.error().to_string().c_str());
      ++problems;
    }
    std::printf("%s\n", problems ? fmt::format("{} problem(s)", problems).c_str() : "ok");
    return problems ? 1 : 0;
  }
  auto read = mesh::read_mesh(options.file);
  if (!read) return fail(read.error());
  std::printf("ok\n");
  return 0;
}

}  // namespace hof::app
