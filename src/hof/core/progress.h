#pragma once
/// @file
/// Progress reporting for long work (meshing, file reading, benchmarks). A ProgressSink is
/// handed down to the code doing the work; the terminal sink draws a single updating line
/// on stderr when it is a terminal, and nothing when quiet.

#include <functional>
#include <string>
#include <string_view>

namespace hof {

/// Receives progress of one named task. `fraction` is in [0, 1]; a negative fraction means
/// "busy, amount unknown". Called from the working thread only.
using ProgressSink = std::function<void(std::string_view task, double fraction)>;

/// A sink that draws "task [#####.....] 50%" on stderr, redrawing in place when stderr is a
/// terminal and printing one line per task otherwise. When `quiet` it prints nothing.
[[nodiscard]] ProgressSink make_terminal_progress(bool quiet);

}  // namespace hof
