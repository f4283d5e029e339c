#include "hof/app/session_recording.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <sys/resource.h>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string_view>
#include <vector>

#include "hof/app/detail/plots.h"
#include "hof/core/text.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh_io.h"
#include "hof/procedures/needle.h"

namespace hof::app {

namespace {

// Text as UTF-8 (a Latin-1 name's bytes become U+FFFD), so that a report (JSON, CSV, the
// terminal) is never refused for a name.
std::string json_safe(std::string_view text) { return valid_utf8(text); }

// A body name as a file name: letters, digits, '-', '_' and '.' kept, anything else '_'.
std::string file_safe(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ? c : '_';
  return out.empty() ? std::string("body") : out;
}

std::string csv_number(double v) { return fmt::format("{:.9g}", v); }

// What hand `h` carries: the first hand's tool or needle, the others' <tool device=…>.
std::string hand_tool_name(const scene::World& world, std::size_t h) {
  if (h == 0) {
    if (world.project.needle) return "needle";
    return world.project.tool ? std::string(procedures::shape_name(world.project.tool->shape)) : "point";
  }
  return h - 1 < world.project.hands.size() ? std::string(procedures::shape_name(world.project.hands[h - 1].tool.shape))
                                            : "point";
}

// What a needle run measured, for the report and its plots.
struct NeedleRun {
  bool mounted{false};
  procedures::TissueNeedleParameters tissue;  // of the first body pierced (else the common set)
  std::string body;                           // that body
  std::array<double, procedures::kNeedlePhaseCount> phase_s{};
  double puncture_depth_m{-1.0};
  double max_depth_m{0.0};
  double peak_before_puncture_n{0.0};
  double force_after_puncture_n{0.0};
  double insertion_speed_sum{0.0};
  std::int64_t insertion_ticks{0};
};

// The model's curves over depth, for the force-against-depth plot: before puncture up to the
// puncture depth (or the capsule), after it from there to the deepest point (Simone–Okamura's
// friction at the mean insertion speed).
void write_needle_model(const std::filesystem::path& dir, const NeedleRun& needle) {
  std::ofstream out(dir / "needle_model.dat");
  out << "# depth_mm,pre_puncture_N,post_puncture_N (" << procedures::model_name(needle.tissue.model) << ")\n";
  const double puncture = needle.puncture_depth_m > 0.0 ? needle.puncture_depth_m : needle.tissue.capsule_m;
  const double deepest = std::max(needle.max_depth_m, puncture);
  const double speed =
      needle.insertion_ticks > 0 ? needle.insertion_speed_sum / static_cast<double>(needle.insertion_ticks) : 0.0;
  constexpr int kPoints = 400;
  for (int i = 0; i <= kPoints; ++i) {
    const double d = deepest * i / kPoints;
    const std::string pre = d <= puncture ? csv_number(procedures::pre_puncture_force(needle.tissue, d)) : "NaN";
    const std::string post =
        d >= puncture ? csv_number(procedures::post_puncture_force(needle.tissue, d, speed, 0.0)) : "NaN";
    out << csv_number(1e3 * d) << "," << pre << "," << post << "\n";
  }
}

// The loading curve of each press (mean force per indentation bin), one column per press:
// the palpation plot compares presses without the noise of single samples.
void write_press_curves(const std::filesystem::path& dir, const coupling::PressRecorder& presses,
                        double to_plot_units) {
  std::ofstream out(dir / "presses.dat");
  out << "# indentation, then the mean loading force (N) of each press (NaN: no sample)\n";
  const auto& all = presses.presses();
  const std::size_t bins = all.empty() ? 0 : all.front().loading_count.size();
  for (std::size_t b = 0; b < bins; ++b) {
    bool any = false;
    std::string row =
        fmt::format("{:.6g}", (static_cast<double>(b) + 0.5) * coupling::PressRecorder::kBinWidthM * to_plot_units);

    const double indentation = (static_cast<double>(b) + 0.5) * coupling::PressRecorder::kBinWidthM;
    for (const coupling::Press& p : all) {
      // Up to the peak force: past it the probe is turning back while the tissue still moves.
      const bool has =
          p.loading_count[b] > 0 && indentation <= p.indentation_at_max_force + coupling::PressRecorder::kBinWidthM;
      any = any || has;
      row += has ? fmt::format(" {:.6g}", p.loading_force_sum[b] / p.loading_count[b]) : std::string(" NaN");
    }
    if (any) out << row << "\n";
  }
}

void write_plots(const std::filesystem::path& dir, const coupling::SessionReport& report, const std::string& title,
                 const std::string& unit, bool quiet, const NeedleRun& needle, const coupling::PressRecorder& presses) {
  const std::size_t press_count = presses.presses().size();
  // Period histogram data (µs, count), every bin that holds a tick. The last bin collects every
  // period past the histogram's range; it is drawn apart, at the longest period, so that a
  // stall of 25 ms is neither off the chart nor shown as 20 ms.
  const auto& period_bins = report.haptic_periods.bins();
  const std::uint32_t beyond_range = period_bins.empty() ? 0u : period_bins.back();
  const double longest_us = 1e6 * report.haptic_periods.max_s();
  {
    std::ofstream h(dir / "haptic_period_histogram.dat");
    for (std::size_t b = 0; b + 1 < period_bins.size(); ++b) {
      if (period_bins[b]) h << b << " " << period_bins[b] << "\n";
    }
    if (beyond_range) h << "\n\n" << longest_us << " " << beyond_range << "\n";
  }
  const double deadline_us = 2000.0;  // the deadline docs/reliability.md holds the loop to
  // In virtual time every tick is the nominal period (nothing is timed): the histogram is one
  // spike, and says so rather than looking like a perfect real-time loop.
  const auto filled_bins = std::ranges::count_if(period_bins, [](std::uint32_t n) { return n > 0; });
  const bool one_period = filled_bins == 1 && !beyond_range;
  const std::string period_series_title = one_period
                                              ? fmt::format("every tick {:.0f} us: virtual time, ticks are not timed",
                                                            1e6 * report.haptic_periods.nominal_s())
                                              : std::string("ticks per 1 us bin");
  const bool metres = unit == "m";
  const std::string length = metres ? "mm" : unit;
  const std::string scale = metres ? "*1000" : "";
  // One small gnuplot script per plot, so that a plot with no data (no contact, say) does not
  // stop the others; plots.gp collects them for the user.
  using detail::Plot;
  std::vector<Plot> plots{
      {"force_over_time",
       "set datafile separator ','\nset xlabel 'time (s)'\nset ylabel 'force (N)'\n"
       "plot 'telemetry.csv' every ::1 using 1:(sqrt($8**2+$9**2+$10**2)) with lines title '|F| sent to the device'\n"},
      {"force_vs_indentation",
       // Each press its own colour (a palpation sweep: the stiff spot stands out); one
       // series when there are too many presses to tell apart.
       fmt::format(
           "set datafile separator ','\nset xlabel 'tissue indentation at the contact, since the press began ({0})'\n"
           "set ylabel 'force (N)'\nset key top left\n{2}",
           length, scale,
           press_count >= 2 && press_count <= 12
               ? fmt::format(
                     "plot for [k=1:{0}] 'telemetry.csv' every ::1 using (($11 > 0 && ${2} == k) ? $14{1} : 1/0):"
                     "(sqrt($8**2+$9**2+$10**2)) with points pt 7 ps 0.3 title sprintf('press %d', k)\n",
                     press_count, scale, needle.mounted ? 20 : 16)
               : fmt::format("plot 'telemetry.csv' every ::1 using ($11 > 0 ? $14{0} : 1/0):(sqrt($8**2+$9**2+$10**2)) "
                             "with points pt 7 ps 0.3 title 'indentation since the press began (in contact)'\n",
                             scale))},
      {"force_vs_penetration",
       fmt::format(
           "set datafile separator ','\nset xlabel 'device-proxy penetration ({})'\nset ylabel 'force (N)'\n"
           "plot 'telemetry.csv' every ::1 using ($11 > 0 ? $12{} : 1/0):(sqrt($8**2+$9**2+$10**2)) with points pt 7 "
           "ps 0.3 title 'renderer spring: proxy - device (in contact)'\n",
           length, scale)},
      {"haptic_period_histogram",
       fmt::format("set xlabel 'haptic period (us)'\nset ylabel 'ticks'\nset logscale y\nset yrange [0.5:*]\n"
                   "set xrange [0:{0:.0f}]\nset style fill solid\nset boxwidth 1\nset key top right\n"
                   "set arrow from {1:.0f}, graph 0 to {1:.0f}, graph 1 nohead dt 2 lc rgb 'red'\n"
                   "set label '2 ms deadline' at {1:.0f}, graph 0.6 offset 0.5, 0 tc rgb 'red'\n"
                   "plot 'haptic_period_histogram.dat' index 0 using 1:2 with boxes title '{3}'{2}\n",
                   1.05 * std::max(longest_us, 1.2 * deadline_us), deadline_us,
                   beyond_range ? fmt::format(", 'haptic_period_histogram.dat' index 1 using 1:2 with impulses lw 4 "
                                              "lc rgb 'red' title '{} ticks of 20 ms or more (longest {:.1f} ms)'",
                                              beyond_range, 1e-3 * longest_us)
                                : std::string(),
                   period_series_title)},
  };
  if (press_count >= 2 && press_count <= 12 && metres) {
    // A palpation sweep: each press's loading curve, titled with where it touched.
    write_press_curves(dir, presses, 1000.0);
    std::string series;
    for (const coupling::Press& p : presses.presses()) {
      series += fmt::format(
          "{}'presses.dat' using 1:{} with linespoints pt 7 ps 0.5 lw 2 title 'press {} at ({:.0f}, {:.0f}) mm'",
          series.empty() ? "" : ", ", p.index + 1, p.index, 1e3 * p.first_contact.x(), 1e3 * p.first_contact.y());
    }
    plots.push_back(
        {"palpation",
         "set xlabel 'tissue indentation at the contact (mm)'\nset ylabel 'force while pressing (N), mean per 0.5 mm'\n"
         "set key top left\nplot " +
             series + "\n"});
  }
  if (needle.mounted) {
    write_needle_model(dir, needle);
    // Columns: 16 depth (m), 17 phase, 18 the model's axial force (N), 19 the force sent along the axis.
    const auto phase_points = [](const std::string& x, const std::string& y) {
      std::string out;
      for (const char* phase : {"pre-puncture", "punctured", "relaxation", "extraction"}) {
        out += fmt::format(
            "'telemetry.csv' every ::1 using (strcol(17) eq '{0}' ? {1} : 1/0):{2} with points pt 7 ps 0.4 title "
            "'{0}', ",
            phase, x, y);
      }
      return out;
    };
    plots.push_back(
        {"force_vs_depth",
         fmt::format(
             "set datafile separator ','\nset xlabel 'needle depth below the entry point (mm)'\n"
             "set ylabel 'force along the needle (N; > 0 resists insertion)'\nset key below\n"
             "plot {}"
             "'needle_model.dat' using 1:2 with lines lw 2 lc rgb 'black' dt 2 title 'model before puncture ({})', "
             "'needle_model.dat' using 1:3 with lines lw 2 lc rgb 'black' dt 3 title 'model after puncture'\n",
             phase_points("$16*1000", "18"), procedures::model_name(needle.tissue.model))});
    plots.push_back(
        {"needle_force_over_time",
         "set datafile separator ','\nset xlabel 'time (s)'\nset ylabel 'force along the needle (N; > 0 resists "
         "insertion)'\n"
         "set y2label 'depth (mm)'\nset y2tics\nset ytics nomirror\nset key below\n"
         "plot " +
             phase_points("$1", "18") +
             "'telemetry.csv' every ::1 using 1:19 with lines lc rgb 'gray40' title 'sent to the device (after "
             "safety)', "
             "'telemetry.csv' every ::1 using 1:($16*1000) axes x1y2 with lines lc rgb 'black' dt 2 title 'depth'\n"});
  }
  std::string failed;
  for (const std::string& name : detail::render_plots(dir, title, plots)) failed += (failed.empty() ? "" : ", ") + name;
  if (!failed.empty() && !quiet) {
    std::fprintf(stderr, "hof: note: no plot for %s (no data, or gnuplot missing); plots.gp is in %s\n", failed.c_str(),
                 dir.c_str());
  }
}

// A CSV field: quoted when it holds a separator or a quote.
std::string csv_text(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

const char* scheduling_name(haptics::HapticLoop::Scheduling s) {
  switch (s) {
    case haptics::HapticLoop::Scheduling::realtime:
      return "SCHED_FIFO";
    case haptics::HapticLoop::Scheduling::refused:
      return "refused (normal priority: run as root or grant CAP_SYS_NICE / rtprio)";
    case haptics::HapticLoop::Scheduling::not_requested:
      return "not requested (virtual time)";
    case haptics::HapticLoop::Scheduling::device_servo:
      return "the device's servo loop";
    case haptics::HapticLoop::Scheduling::not_started:
      break;
  }
  return "not started";
}

// Ticks whose period exceeded `limit_s` (a missed haptic deadline), from the 1 µs histogram.
std::uint64_t periods_over(const haptics::PeriodStats& periods, double limit_s) {
  std::uint64_t n = 0;
  const auto& bins = periods.bins();
  for (std::size_t b = static_cast<std::size_t>(limit_s * 1e6) + 1; b < bins.size(); ++b) n += bins[b];
  return n;
}

}  // namespace

double default_run_seconds(const coupling::Session& session) {
  const double script_s = session.haptic_loop().device().script_duration_s();
  return script_s > 5.0 ? std::min(script_s + 0.5, 3600.0) : 5.0;
}

struct RunRecording::Impl {
  const coupling::Session& session;
  const scene::World& world;
  double telemetry_rate_hz{0.0};
  std::vector<std::string> body_names;  // CSV-safe
  NeedleRun needle;
  std::vector<procedures::TissueNeedleParameters> needle_tissues;
  bool previous_broken{false};
  double next_row{0.0};
  coupling::PressRecorder presses;
  TelemetryRow row;
  double max_force_n{0.0};

  Impl(const coupling::Session& s, const scene::World& w, double rate, double metres_per_unit)
      : session(s), world(w), telemetry_rate_hz(rate), presses(s, metres_per_unit) {}
};

namespace {

// Metres per length unit of the world (the presses' bins are 0.5 mm). A SOFA scene states no
// unit: then its size stands in, as if it were an organ of 25 cm.
double metres_per_unit(const coupling::Session& session, const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "cm") return 0.01;
  if (unit == "mm") return 0.001;
  if (unit == "dm") return 0.1;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max()), hi = -lo;
  for (std::size_t i = 0; i < session.body_count(); ++i) {
    for (const Vec3& p : session.body(i).surface.vertices) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const double size = (hi - lo).norm();
  return size > 0.0 && std::isfinite(size) ? 0.25 / size : 1.0;
}

}  // namespace

RunRecording::RunRecording(const coupling::Session& session, const scene::World& world, double telemetry_rate_hz)
    : impl_(std::make_unique<Impl>(session, world, telemetry_rate_hz, metres_per_unit(session, world.length_unit))) {
  Impl& m = *impl_;
  for (std::size_t i = 0; i < session.body_count(); ++i)
    m.body_names.push_back(csv_text(json_safe(session.body(i).name)));
  if (world.project.needle) {
    m.needle.mounted = true;
    std::vector<std::string> names;
    std::vector<bool> deformable;
    for (std::size_t i = 0; i < session.body_count(); ++i) {
      names.push_back(session.body(i).name);
      deformable.push_back(session.body(i).deformable());
    }
    m.needle_tissues = procedures::parameters_by_body(*world.project.needle, names, deformable);
    m.needle.tissue = world.project.needle->tissue;
  }
  // The limit the safety filter holds: the device's, or the project's when lower.
  const double device_max = session.haptic_loop().device().spec().max_force_n;
  const double project_max = world.config.haptics.safety.max_force_n;
  m.max_force_n = project_max > 0.0 ? std::min(device_max, project_max) : device_max;
}

RunRecording::~RunRecording() = default;

const TelemetryRow* RunRecording::add(const haptics::HapticSample& s) {
  Impl& m = *impl_;
  NeedleRun& needle = m.needle;
  if (needle.mounted && s.valid) {
    const auto phase = static_cast<procedures::NeedlePhase>(s.tool.phase);
    needle.phase_s[static_cast<std::size_t>(phase)] += s.period_s;
    if (needle.body.empty() && s.tool.body >= 0 && static_cast<std::size_t>(s.tool.body) < m.needle_tissues.size()) {
      needle.body = m.session.body(static_cast<std::size_t>(s.tool.body)).name;
      needle.tissue = m.needle_tissues[static_cast<std::size_t>(s.tool.body)];
    }
    needle.max_depth_m = std::max(needle.max_depth_m, s.tool.depth_m);
    if (phase == procedures::NeedlePhase::kPrePuncture)
      needle.peak_before_puncture_n = std::max(needle.peak_before_puncture_n, s.tool.axial_force_n);
    if (s.tool.broken && !m.previous_broken && needle.puncture_depth_m < 0.0) {
      needle.puncture_depth_m = s.tool.depth_m;
      needle.force_after_puncture_n = s.tool.axial_force_n;
    }
    if (phase == procedures::NeedlePhase::kPunctured) {
      needle.insertion_speed_sum += s.device_velocity.dot(s.tool.axis);
      ++needle.insertion_ticks;
    }
    m.previous_broken = s.tool.broken;
  }
  // Indentation: how far the tissue surface at the contact has moved inward since the press
  // began (press_recorder.h); each press numbered, for palpation.
  const double indentation = m.presses.add(s);
  // No reading (a script that has ended, a device gone): not a device at the origin.
  if (!s.valid) return nullptr;
  if (m.telemetry_rate_hz > 0.0) {
    if (s.time_s + 1e-12 < m.next_row) return nullptr;
    m.next_row += 1.0 / m.telemetry_rate_hz;
  }
  TelemetryRow& row = m.row;
  row.time_s = s.time_s;
  row.device = s.device;
  row.proxy = s.proxy;
  row.force = s.force;
  row.contact = s.contact;
  row.penetration_m = s.penetration_m;
  row.period_s = s.period_s;
  row.indentation_m = indentation;
  row.body = s.contact && s.triangle >= 0 ? m.session.body_of_triangle(s.triangle, s.layer) : -1;
  if (s.tool.body >= 0 && static_cast<std::size_t>(s.tool.body) < m.body_names.size()) row.body = s.tool.body;
  row.press = m.presses.current();
  row.needle_depth_m = s.tool.depth_m;
  row.needle_phase = s.tool.phase;
  row.needle_force_n = s.tool.axial_force_n;
  row.sent_axial_force_n = s.tool.axis.squaredNorm() > 0.0 ? -s.force.dot(s.tool.axis) : 0.0;
  return &row;
}

bool RunRecording::needle_mounted() const { return impl_->needle.mounted; }

std::vector<std::string> RunRecording::column_names() const {
  std::vector<std::string> names{"t",       "device_x",    "device_y", "device_z",    "proxy_x",
                                 "proxy_y", "proxy_z",     "force_x",  "force_y",     "force_z",
                                 "contact", "penetration", "period",   "indentation", "body"};
  // With a needle: its depth, phase, the model's force along it and the force sent along it.
  if (needle_mounted()) names.insert(names.end(), {"depth", "phase", "needle_force", "sent_axial_force"});
  // The press the sample belongs to (1, 2, ...; 0 between presses): palpation.
  names.emplace_back("press");
  return names;
}

std::string RunRecording::csv_header() const {
  std::string line;
  for (const std::string& name : column_names()) line += (line.empty() ? "" : ",") + name;
  return line + "\n";
}

std::string RunRecording::csv_row(const TelemetryRow& r) const {
  const std::string& body = r.body >= 0 && static_cast<std::size_t>(r.body) < impl_->body_names.size()
                                ? impl_->body_names[static_cast<std::size_t>(r.body)]
                                : std::string();
  std::string line = fmt::format(
      "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", csv_number(r.time_s), csv_number(r.device.x()),
      csv_number(r.device.y()), csv_number(r.device.z()), csv_number(r.proxy.x()), csv_number(r.proxy.y()),
      csv_number(r.proxy.z()), csv_number(r.force.x()), csv_number(r.force.y()), csv_number(r.force.z()),
      r.contact ? 1 : 0, csv_number(r.penetration_m), csv_number(r.period_s), csv_number(r.indentation_m), body);
  if (needle_mounted()) {
    line += fmt::format(",{},{},{},{}", csv_number(r.needle_depth_m),
                        procedures::phase_name(static_cast<procedures::NeedlePhase>(r.needle_phase)),
                        csv_number(r.needle_force_n), csv_number(r.sent_axial_force_n));
  }
  return line + fmt::format(",{}\n", r.press);
}

const std::vector<std::string>& RunRecording::body_names() const { return impl_->body_names; }
const coupling::PressRecorder& RunRecording::presses() const { return impl_->presses; }
double RunRecording::max_force_n() const { return impl_->max_force_n; }

double RunRecording::clamped_share(const coupling::SessionReport& report) const {
  return report.contact_time_s > 0.0 ? static_cast<double>(report.clamped_contact_ticks) *
                                           impl_->session.haptic_loop().nominal_period_s() / report.contact_time_s
                                     : 0.0;
}

std::string RunRecording::summary_json(const coupling::SessionReport& report, const RunConditions& conditions) const {
  const Impl& m = *impl_;
  const coupling::Session& session = m.session;
  const scene::World& world = m.world;
  const NeedleRun& needle = m.needle;
  const auto& periods = report.haptic_periods;
  nlohmann::json summary;
  summary["file"] = json_safe(world.file.string());
  summary["scene"] = json_safe(world.scene_path.string());
  summary["name"] = json_safe(world.name);
  summary["length_unit"] = world.length_unit;
  summary["mode"] = conditions.deterministic ? "virtual-time (deterministic)" : "real-time";
  summary["device"] = json_safe(world.device);
  summary["default_probe"] = world.default_probe;
  summary["simulated_s"] = report.simulated_s;
  summary["wall_s"] = report.wall_s;
  summary["haptic"] = {
      {"ticks", report.haptic_ticks},
      {"rate_hz", periods.rate_hz()},
      {"nominal_period_s", periods.nominal_s()},
      {"period_p50_s", periods.quantile_s(0.5)},
      {"period_p99_s", periods.quantile_s(0.99)},
      {"period_max_s", periods.max_s()},
      {"overruns", periods.overruns()},
      {"periods_over_2ms", periods_over(periods, 2e-3)},
      {"scheduling", scheduling_name(session.haptic_loop().scheduling())},
      {"memory_locked", conditions.memory_locked},
      {"cpus_kept_awake", conditions.cpus_kept_awake},
      {"keep_awake", conditions.keep_awake},
      {"cpu_placement", conditions.deterministic ? "not pinned (virtual time)" : report.cpu_placement}};
  if (conditions.host_cpu_steal_s) summary["host_cpu_steal_s"] = *conditions.host_cpu_steal_s;
  // Peak resident memory of the process (getrusage reports KiB on Linux): a soak compares it
  // with the memory early in the run.
  if (rusage usage{}; ::getrusage(RUSAGE_SELF, &usage) == 0)
    summary["peak_rss_bytes"] = static_cast<std::int64_t>(usage.ru_maxrss) * 1024;
  summary["simulation"] = {{"steps", report.simulation_steps},
                           {"dt_s", session.dt()},
                           {"steps_per_s", report.simulation_steps_per_s},
                           {"threads", conditions.deterministic ? 1 : report.simulation_threads}};
  summary["graphics_equivalent_fps"] = {{"untouched", report.rate_untouched},
                                        {"deforming", report.rate_deforming},
                                        {"in_contact", report.rate_in_contact}};
  summary["max_force_n"] = report.max_force_n;
  summary["contact_time_s"] = report.contact_time_s;
  summary["contact_time_at_force_limit_share"] = clamped_share(report);
  summary["fall_through_events"] = report.fall_through_events;
  summary["diverged"] = report.diverged;
  if (report.diverged) summary["divergence"] = json_safe(report.divergence);
  if (!report.device_failure.empty()) summary["device_failure"] = json_safe(report.device_failure);
  summary["safety"] = {{"clamped_ticks", report.safety.clamped},
                       {"rate_limited_ticks", report.safety.rate_limited},
                       {"non_finite_ticks", report.safety.non_finite},
                       {"no_reading_ticks", report.safety.no_reading},
                       {"watchdog_ticks", report.safety.watchdog}};
  nlohmann::json bodies = nlohmann::json::array();
  for (const coupling::BodyReport& b : report.bodies) {
    bodies.push_back({{"name", json_safe(b.name)},
                      {"kind", b.deformable ? "deformable" : "rigid"},
                      {"nodes", b.nodes},
                      {"max_displacement", b.max_displacement_m},
                      {"contact_time_s", b.contact_time_s},
                      {"max_force_n", b.max_force_n},
                      {"fall_through_events", b.fall_through_events},
                      {"probe_started_inside", b.probe_started_inside}});
  }
  summary["bodies"] = bodies;
  // Two hands or more (<tool device=…>): each hand's figures (the ones above are the first's).
  // Not written for one device, whose report stays as it was.
  if (report.hands.size() >= 2) {
    nlohmann::json hands = nlohmann::json::array();
    for (std::size_t h = 0; h < report.hands.size(); ++h) {
      const coupling::HandReport& hand = report.hands[h];
      hands.push_back({{"device", json_safe(hand.device)},
                       {"tool", hand_tool_name(world, h)},
                       {"haptic_ticks", hand.haptic_ticks},
                       {"max_force_n", hand.max_force_n},
                       {"force_limit_n", hand.max_force_limit_n},
                       {"contact_time_s", hand.contact_time_s},
                       {"clamped_contact_ticks", hand.clamped_contact_ticks},
                       {"safety",
                        {{"clamped_ticks", hand.safety.clamped},
                         {"rate_limited_ticks", hand.safety.rate_limited},
                         {"non_finite_ticks", hand.safety.non_finite},
                         {"no_reading_ticks", hand.safety.no_reading},
                         {"watchdog_ticks", hand.safety.watchdog}}}});
    }
    summary["hands"] = hands;
  }
  // The single-body key of earlier reports (kept for scripts that read it).
  summary["models"] = nlohmann::json::array();
  for (const coupling::BodyReport& b : report.bodies) {
    summary["models"].push_back(
        {{"name", json_safe(b.name)}, {"nodes", b.nodes}, {"max_displacement_m", b.max_displacement_m}});
  }
  summary["skipped_components"] = nlohmann::json::array();
  for (const auto& s : world.skipped) summary["skipped_components"].push_back(json_safe(s));
  summary["ignored_components"] = nlohmann::json::array();
  for (const auto& s : world.ignored) summary["ignored_components"].push_back(json_safe(s));
  summary["defaults"] = nlohmann::json::array();
  for (const auto& d : world.defaults) summary["defaults"].push_back(json_safe(d));
  summary["commands"] = report.applied_commands;
  // The presses: where, how deep, how hard, how stiff (a tumour: stiffer than elsewhere).
  summary["presses"] = nlohmann::json::array();
  for (const coupling::Press& p : m.presses.presses()) {
    summary["presses"].push_back(
        {{"index", p.index},
         {"body", p.body >= 0 ? nlohmann::json(json_safe(session.body(static_cast<std::size_t>(p.body)).name))
                              : nlohmann::json()},
         {"start_s", p.start_s},
         {"end_s", p.end_s},
         {"first_contact", {p.first_contact.x(), p.first_contact.y(), p.first_contact.z()}},
         {"max_force_n", p.max_force_n},
         {"max_indentation", p.max_indentation_m},
         {"stiffness", p.stiffness}});
  }
  if (needle.mounted) {
    nlohmann::json phases = nlohmann::json::object();
    for (int k = 0; k < procedures::kNeedlePhaseCount; ++k) {
      phases[std::string(procedures::phase_name(static_cast<procedures::NeedlePhase>(k)))] =
          needle.phase_s[static_cast<std::size_t>(k)];
    }
    summary["needle"] = {{"model", procedures::model_name(needle.tissue.model)},
                         {"body", json_safe(needle.body)},
                         {"phase_time_s", phases},
                         {"max_depth_m", needle.max_depth_m},
                         {"puncture_depth_m",
                          needle.puncture_depth_m > 0.0 ? nlohmann::json(needle.puncture_depth_m) : nlohmann::json()},
                         {"peak_force_before_puncture_n", needle.peak_before_puncture_n},
                         {"force_after_puncture_n", needle.force_after_puncture_n},
                         {"capsule_m", needle.tissue.capsule_m},
                         {"puncture_force_n", needle.tissue.puncture_force_n}};
  }
  if (!conditions.telemetry_problem.empty()) summary["telemetry_problem"] = conditions.telemetry_problem;
  if (!conditions.stopped_by.empty()) summary["stopped_by"] = conditions.stopped_by;
  return summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

bool RunRecording::write_report_files(const std::filesystem::path& dir, const coupling::SessionReport& report,
                                      bool quiet) const {
  const coupling::Session& session = impl_->session;
  bool ok = true;
  for (std::size_t i = 0; i < session.body_count(); ++i) {
    const coupling::SessionBody& body = session.body(i);
    if (!body.deformable()) continue;
    mesh::Mesh final_state;
    const auto& state = session.state(i);
    for (std::size_t n = 0; n < body.model->node_count(); ++n)
      final_state.nodes.push_back(state.position(static_cast<std::int32_t>(n)));
    final_state.tets = body.model->tets;
    // A hexahedral model as its boundary (the mesh files hold tetrahedra and triangles).
    if (!body.model->hexahedra.empty())
      final_state.triangles = mesh::hex_boundary(body.model->rest_positions, body.model->hexahedra).volume_triangles;
    else if (final_state.tets.empty())
      final_state.triangles = body.model->triangles;
    if (auto written = mesh::write_vtu(final_state, dir / (file_safe(body.name) + ".vtu")); !written) {
      std::fprintf(stderr, "hof: %s\n", written.error().to_string().c_str());
      ok = false;  // the rest of the report is still written
    }
  }
  std::string touched;
  for (const coupling::BodyReport& b : report.bodies) {
    if (b.contact_time_s > 0.0) touched += (touched.empty() ? "" : ", ") + json_safe(b.name);
  }
  // Titled by what the user ran (the project), with the scene it loads when that differs:
  // several projects over one scene must not draw plots that read alike.
  const std::filesystem::path& ran = impl_->world.file;
  const std::filesystem::path& scene_file = impl_->world.scene_path;
  const std::string source =
      ran.empty() || ran.filename() == scene_file.filename()
          ? scene_file.filename().string()
          : fmt::format("{} (scene {})", ran.filename().string(), scene_file.filename().string());
  write_plots(dir, report, fmt::format("{} - {}", json_safe(source), touched.empty() ? "no contact" : touched),
              impl_->world.length_unit, quiet, impl_->needle, impl_->presses);
  return ok;
}

void RunRecording::print(const coupling::SessionReport& report, bool deterministic,
                         const std::optional<std::filesystem::path>& out) const {
  const scene::World& world = impl_->world;
  const NeedleRun& needle = impl_->needle;
  const auto& periods = report.haptic_periods;
  const bool metres = world.length_unit == "m";
  const auto length = [&](double v) {
    return metres ? fmt::format("{:.2f} mm", 1e3 * v) : fmt::format("{:.4g} {}", v, world.length_unit);
  };
  std::printf("%s: %.2f s simulated in %.2f s (%s)\n", world.file.c_str(), report.simulated_s, report.wall_s,
              deterministic ? "virtual time" : "real time");
  if (world.default_probe) std::printf("  device      the default probe: %s\n", world.device.c_str());
  std::printf("  haptic      %lld ticks, %.0f Hz, period p50 %.1f us, p99 %.1f us, max %.1f us, %llu overruns\n",
              static_cast<long long>(report.haptic_ticks), periods.rate_hz(), 1e6 * periods.quantile_s(0.5),
              1e6 * periods.quantile_s(0.99), 1e6 * periods.max_s(),
              static_cast<unsigned long long>(periods.overruns()));
  if (deterministic) {
    std::printf("  simulation  %lld steps, %.0f steps/s\n", static_cast<long long>(report.simulation_steps),
                report.simulation_steps_per_s);
  } else {
    std::printf("  simulation  %lld steps, %.0f steps/s on %d thread%s (%s)\n",
                static_cast<long long>(report.simulation_steps), report.simulation_steps_per_s,
                report.simulation_threads, report.simulation_threads == 1 ? "" : "s", report.cpu_placement.c_str());
  }
  std::printf("  contact     %.3f s, max force %.3f N, fall-through events %lld\n", report.contact_time_s,
              report.max_force_n, static_cast<long long>(report.fall_through_events));
  for (const coupling::BodyReport& b : report.bodies) {
    std::printf("  body        %s (%s): contact %.3f s, max force %.3f N%s%s\n", json_safe(b.name).c_str(),
                b.deformable ? "deformable" : "rigid", b.contact_time_s, b.max_force_n,
                b.deformable ? (", max displacement " + length(b.max_displacement_m)).c_str() : "",
                b.probe_started_inside ? ", the probe started inside it" : "");
    if (b.max_body_contacts > 0) {
      std::printf(
          "              contact with bodies: %lld contacts at the end (at most %lld), force (%.3f, %.3f, %.3f) N "
          "(largest %.3f N)\n",
          static_cast<long long>(b.body_contacts), static_cast<long long>(b.max_body_contacts),
          b.body_contact_force_n.x(), b.body_contact_force_n.y(), b.body_contact_force_n.z(),
          b.max_body_contact_force_n);
    }
  }
  if (report.hands.size() >= 2) {
    for (std::size_t h = 0; h < report.hands.size(); ++h) {
      const coupling::HandReport& hand = report.hands[h];
      std::printf(
          "  hand %zu      %s on %s: contact %.3f s, max force %.3f N (limit %.3f N), clamped %lld contact ticks, "
          "safety: %llu clamped, %llu no reading, %llu watchdog\n",
          h + 1, hand_tool_name(world, h).c_str(), json_safe(hand.device).c_str(), hand.contact_time_s,
          hand.max_force_n, hand.max_force_limit_n, static_cast<long long>(hand.clamped_contact_ticks),
          static_cast<unsigned long long>(hand.safety.clamped), static_cast<unsigned long long>(hand.safety.no_reading),
          static_cast<unsigned long long>(hand.safety.watchdog));
    }
  }
  if (report.friction_solved_as_penalty)
    std::printf("  contact     friction contact is not simulated yet: solved as penalty springs without friction\n");
  if (needle.mounted) {
    std::string visited;
    for (int k = 0; k < procedures::kNeedlePhaseCount; ++k) {
      const double t = needle.phase_s[static_cast<std::size_t>(k)];
      if (t > 0.0)
        visited += fmt::format("{}{} {:.2f} s", visited.empty() ? "" : ", ",
                               procedures::phase_name(static_cast<procedures::NeedlePhase>(k)), t);
    }
    std::printf("  needle      %s model%s: %s\n", std::string(procedures::model_name(needle.tissue.model)).c_str(),
                needle.body.empty() ? "" : (" in " + json_safe(needle.body)).c_str(), visited.c_str());
    if (needle.puncture_depth_m > 0.0) {
      std::printf("              capsule broken at %s (%.3f N before, %.3f N after); deepest %s\n",
                  length(needle.puncture_depth_m).c_str(), needle.peak_before_puncture_n, needle.force_after_puncture_n,
                  length(needle.max_depth_m).c_str());
    } else {
      std::printf("              capsule intact; deepest %s, peak %.3f N\n", length(needle.max_depth_m).c_str(),
                  needle.peak_before_puncture_n);
    }
  }
  if (impl_->presses.presses().size() >= 2) {
    // A palpation sweep: each press's stiffness, the stiffest named (a lump to look at).
    const auto& all = impl_->presses.presses();
    const auto stiffest = std::ranges::max_element(all, {}, [](const coupling::Press& p) { return p.stiffness; });
    std::string list;
    for (const coupling::Press& p : all) list += fmt::format("{}{:.0f}", list.empty() ? "" : ", ", p.stiffness);
    std::printf("  presses     %zu, stiffness %s N/%s; stiffest: press %d, first touched at (%s)\n", all.size(),
                list.c_str(), world.length_unit.c_str(), stiffest->index,
                fmt::format("{:.4g}, {:.4g}, {:.4g}", stiffest->first_contact.x(), stiffest->first_contact.y(),
                            stiffest->first_contact.z())
                    .c_str());
  }
  if (report.diverged) std::printf("  DIVERGED    %s\n", report.divergence.c_str());
  if (!report.device_failure.empty())
    std::printf("  DEVICE      failed, the run ended: %s\n", json_safe(report.device_failure).c_str());
  if (out)
    std::printf("  report      %s (telemetry.csv, summary.json, .vtu per deformable body, plots)\n", out->c_str());
}

void RunRecording::print_warnings(const coupling::SessionReport& report, bool deterministic, bool quiet) const {
  // A run that ended before the default probe arrived touched nothing, and would say nothing
  // of why: name the time it needs.
  const scene::World& world = impl_->world;
  if (world.default_probe && world.probe_arrival_s > 0.0 && report.contact_time_s <= 0.0 &&
      report.simulated_s < world.probe_arrival_s) {
    std::fprintf(stderr,
                 "hof: warning: the run ended after %.2f s, before the default probe reached the surface: it needs "
                 "about %.1f s to arrive and %.1f s for its whole press (--seconds %.0f, or leave --seconds out)\n",
                 report.simulated_s, world.probe_arrival_s, world.probe_press_s, std::ceil(world.probe_press_s));
  }
  // A device that never gave a reading (a UDP bridge that is not sending, say): the run
  // touched nothing and its plots are empty; say why rather than only that plots are missing.
  if (report.haptic_ticks > 0 && report.safety.no_reading >= static_cast<std::uint64_t>(report.haptic_ticks)) {
    std::fprintf(stderr,
                 "hof: warning: the device gave no reading in the whole run (%lld ticks): nothing was touched; "
                 "is it connected and sending (device %s)?\n",
                 static_cast<long long>(report.haptic_ticks), json_safe(world.device).c_str());
  }
  const double clamped = clamped_share(report);
  if (clamped > 0.01) {
    std::fprintf(stderr,
                 "hof: warning: the force was at the device's limit (%.1f N) for %.0f%% of the contact time: the "
                 "surface is too stiff for this device or the press too deep\n",
                 impl_->max_force_n, 100.0 * clamped);
  }
  if (!deterministic && !quiet &&
      impl_->session.haptic_loop().scheduling() == haptics::HapticLoop::Scheduling::refused) {
    std::fprintf(stderr,
                 "hof: note: the haptic thread ran at normal priority (real-time scheduling was refused): on a "
                 "busy machine its period can stretch; run as root or grant rtprio (docs/reliability.md)\n");
  }
  std::string started_inside;
  for (const coupling::BodyReport& b : report.bodies) {
    if (b.probe_started_inside) started_inside += (started_inside.empty() ? "" : ", ") + json_safe(b.name);
  }
  if (!started_inside.empty()) {
    std::fprintf(stderr, "hof: warning: the device started inside %s (not counted as fall-through)\n",
                 started_inside.c_str());
  }
}

}  // namespace hof::app
