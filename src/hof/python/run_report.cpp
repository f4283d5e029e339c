#include "hof/python/run_report.h"

#include <system_error>

#include "hof/core/file_write.h"
#include "hof/procedures/needle.h"

namespace hof::python {

// The telemetry as columns named as telemetry.csv's: float64 arrays, `contact` bool,
// `press` int32, `body` (and a needle's `phase`) str arrays.
py::dict columns(const app::RunRecording& recording, const Telemetry& telemetry, const coupling::Session& session) {
  const auto n = static_cast<py::ssize_t>(telemetry.rows.size());
  py::dict d;
  const auto number = [&](const char* name, auto get) {
    py::array_t<double> a(n);
    double* p = a.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i) p[i] = get(telemetry.rows[static_cast<std::size_t>(i)]);
    d[name] = a;
  };
  using Row = app::TelemetryRow;
  number("t", [](const Row& r) { return r.time_s; });
  number("device_x", [](const Row& r) { return r.device.x(); });
  number("device_y", [](const Row& r) { return r.device.y(); });
  number("device_z", [](const Row& r) { return r.device.z(); });
  number("proxy_x", [](const Row& r) { return r.proxy.x(); });
  number("proxy_y", [](const Row& r) { return r.proxy.y(); });
  number("proxy_z", [](const Row& r) { return r.proxy.z(); });
  number("force_x", [](const Row& r) { return r.force.x(); });
  number("force_y", [](const Row& r) { return r.force.y(); });
  number("force_z", [](const Row& r) { return r.force.z(); });
  {
    py::array_t<bool> a(n);
    for (py::ssize_t i = 0; i < n; ++i) a.mutable_data()[i] = telemetry.rows[static_cast<std::size_t>(i)].contact;
    d["contact"] = a;
  }
  number("penetration", [](const Row& r) { return r.penetration_m; });
  number("period", [](const Row& r) { return r.period_s; });
  number("indentation", [](const Row& r) { return r.indentation_m; });
  py::list bodies;
  for (const Row& r : telemetry.rows)
    bodies.append(r.body >= 0 ? session.body(static_cast<std::size_t>(r.body)).name : std::string());
  d["body"] = py::module_::import("numpy").attr("array")(bodies, "str");
  if (recording.needle_mounted()) {
    number("depth", [](const Row& r) { return r.needle_depth_m; });
    py::list phases;
    for (const Row& r : telemetry.rows)
      phases.append(std::string(procedures::phase_name(static_cast<procedures::NeedlePhase>(r.needle_phase))));
    d["phase"] = py::module_::import("numpy").attr("array")(phases, "str");
    number("needle_force", [](const Row& r) { return r.needle_force_n; });
    number("sent_axial_force", [](const Row& r) { return r.sent_axial_force_n; });
  }
  py::array_t<std::int32_t> press(n);
  for (py::ssize_t i = 0; i < n; ++i) press.mutable_data()[i] = telemetry.rows[static_cast<std::size_t>(i)].press;
  d["press"] = press;
  return d;
}

// The report folder `hof run --out` writes: telemetry.csv, summary.json, the shapes, the plots.
void write_report(const std::filesystem::path& dir, const app::RunRecording& recording,
                  const coupling::SessionReport& report, const std::string& summary, const Telemetry& telemetry,
                  bool quiet) {
  py::gil_scoped_release release;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  std::string csv = recording.csv_header();
  for (const app::TelemetryRow& row : telemetry.rows) csv += recording.csv_row(row);
  Expected<void> written = write_file_atomically(dir / "telemetry.csv", csv);
  if (written) written = write_file_atomically(dir / "summary.json", summary);
  if (written) recording.write_report_files(dir, report, quiet);
  if (!written) {
    py::gil_scoped_acquire gil;
    raise(written.error());
  }
}

}  // namespace hof::python
