#pragma once
// A Python run's telemetry: as numpy columns (what World.run returns) and as the report folder
// `hof run --out` writes.

#include <pybind11/numpy.h>

#include <filesystem>
#include <string>
#include <vector>

#include "hof/app/session_recording.h"
#include "hof/coupling/session.h"
#include "hof/python/common.h"

namespace hof::python {

/// The rows a run recorded.
struct Telemetry {
  std::vector<app::TelemetryRow> rows;
};

// The telemetry as columns named as telemetry.csv's: float64 arrays, `contact` bool,
// `press` int32, `body` (and a needle's `phase`) str arrays.
py::dict columns(const app::RunRecording& recording, const Telemetry& telemetry, const coupling::Session& session);

// The report folder `hof run --out` writes: telemetry.csv, summary.json, the shapes, the plots.
void write_report(const std::filesystem::path& dir, const app::RunRecording& recording,
                  const coupling::SessionReport& report, const std::string& summary, const Telemetry& telemetry,
                  bool quiet);

}  // namespace hof::python
