#include "hof/core/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace hof {

namespace {

struct TerminalProgress {
  bool interactive{false};
  std::string current_task;
  int last_percent{-1};

  void update(std::string_view task, double fraction) {
    const bool new_task = task != current_task;
    if (new_task) {
      if (interactive && !current_task.empty()) std::fputc('\n', stderr);
      current_task = std::string(task);
      last_percent = -2;
    }
    const int percent = fraction < 0 ? -1 : static_cast<int>(std::lround(std::min(fraction, 1.0) * 100));
    if (percent == last_percent) return;
    last_percent = percent;
    if (!interactive) {
      // A log file gets one line when a task starts and one when it ends.
      if (new_task)
        std::fprintf(stderr, "%s ...\n", current_task.c_str());
      else if (percent == 100)
        std::fprintf(stderr, "%s done\n", current_task.c_str());
      return;
    }
    constexpr int kWidth = 30;
    char bar[kWidth + 1];
    const int filled = percent < 0 ? 0 : percent * kWidth / 100;
    for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
    bar[kWidth] = '\0';
    if (percent < 0) {
      std::fprintf(stderr, "\r%-40s ...", current_task.c_str());
    } else {
      std::fprintf(stderr, "\r%-40s [%s] %3d%%", current_task.c_str(), bar, percent);
    }
    if (percent == 100) {
      std::fputc('\n', stderr);
      current_task.clear();
    }
    std::fflush(stderr);
  }
};

}  // namespace

ProgressSink make_terminal_progress(bool quiet) {
  if (quiet) return [](std::string_view, double) {};
  auto state = std::make_shared<TerminalProgress>();
  state->interactive = isatty(fileno(stderr)) != 0;
  return [state](std::string_view task, double fraction) { state->update(task, fraction); };
}

}  // namespace hof
