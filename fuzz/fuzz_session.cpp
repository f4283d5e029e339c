// libFuzzer target, end to end: a scene or project file (an archive input, fuzz_common.h: the
// main file first — named NAME.hof, .scn or .x3d by its "@@file" line, else scene.scn — then
// the files it links) run as `hof run FILE --deterministic --steps N --out DIR` does, through
// `hof run`'s own code. The promise checked: the run ends with an error naming the file, or
// its report (summary.json, telemetry.csv, plots.gp) is written.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string_view>

#include "fuzz_common.h"
#include "hof/app/run_command.h"

namespace {

// The plots are drawn by running gnuplot once per plot and format: a few hundred
// milliseconds per input that would test gnuplot, not HoF. The scripts (plots.gp) are still
// written; only the program is not found.
const bool no_gnuplot = [] { return ::setenv("PATH", "/nonexistent", 1) == 0; }();

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)no_gnuplot;
  std::filesystem::path path = hof::fuzz::write_archive(data, size, "scene.scn", /*keep_main_name=*/true);
  const std::string ext = path.extension().string();
  if (ext != ".hof" && ext != ".scn" && ext != ".x3d") {
    const std::filesystem::path renamed = path.parent_path() / (path.stem().string() + ".scn");
    std::error_code ec;
    std::filesystem::rename(path, renamed, ec);
    path = renamed;
  }
  hof::app::RunOptions options;
  options.file = path;
  options.deterministic = true;
  options.steps = 10;  // each a simulation step (at most dt = 1 s each: ≤ 10 s of 1 kHz ticks)
  options.out = hof::fuzz::scratch() / "report";
  options.quiet = true;
  // A UDP device waits for its peer on the network, which is not what this target tests
  // (fuzz_udp covers its datagrams): such a file runs with the default scripted probe.
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (text.find("udp") != std::string_view::npos || text.find("mouse") != std::string_view::npos) {
    options.device = "scripted:poke";
  }
  const int status = hof::app::run_session(options);
  if (status == 0 || status == 2) {
    // A run that went ahead (2: it diverged, which a report states) has its report.
    for (const char* name : {"summary.json", "telemetry.csv", "plots.gp"}) {
      if (!std::filesystem::exists(*options.out / name)) {
        std::fprintf(stderr, "run returned %d but its report has no %s\n", status, name);
        std::abort();
      }
    }
  }
  return 0;
}
