// The terminal progress sink (src/hof/core/progress.cpp) as a log file sees it (stderr not a
// terminal: ctest, CI, a redirect): one line when a task starts and one when it ends, nothing
// in between and nothing at all when quiet.

#include "hof/core/progress.h"

#include <gtest/gtest.h>

#include <string>

namespace hof {
namespace {

std::string captured(bool quiet, void (*work)(const ProgressSink&)) {
  ::testing::internal::CaptureStderr();  // stderr is a file now, so the sink is non-interactive
  const ProgressSink sink = make_terminal_progress(quiet);
  work(sink);
  return ::testing::internal::GetCapturedStderr();
}

TEST(TerminalProgress, ALogGetsOneLineWhenATaskStartsAndOneWhenItEnds) {
  const std::string log = captured(false, [](const ProgressSink& sink) {
    for (int i = 0; i <= 100; ++i) sink("reading liver.msh", i / 100.0);
    sink("tetrahedralizing", -1.0);  // busy, amount unknown
    sink("tetrahedralizing", 0.5);
    sink("tetrahedralizing", 1.0);
  });
  EXPECT_EQ(log, "reading liver.msh ...\nreading liver.msh done\ntetrahedralizing ...\ntetrahedralizing done\n");
}

TEST(TerminalProgress, AFractionPastOneCountsAsDoneOnce) {
  const std::string log = captured(false, [](const ProgressSink& sink) {
    sink("meshing", 0.0);
    sink("meshing", 1.7);
    sink("meshing", 1.0);
  });
  EXPECT_EQ(log, "meshing ...\nmeshing done\n");
}

TEST(TerminalProgress, QuietPrintsNothing) {
  const std::string log = captured(true, [](const ProgressSink& sink) {
    sink("reading", 0.0);
    sink("reading", 1.0);
  });
  EXPECT_EQ(log, "");
}

}  // namespace
}  // namespace hof
