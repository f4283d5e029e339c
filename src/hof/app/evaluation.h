#pragma once
/// @file
/// `hof bench` without a scene: the thesis' evaluation (its Figures 29–33) re-run on this
/// machine, and the haptic-rate goals of the mechanics. Each cell of the matrix is timed in
/// batches (median, min, max steps/s), checked for stability over a span of simulated time,
/// and, where a solver is inexact, compared with an exact LDLᵀ solve of the same step. The
/// tables go to stdout; results.json, results.csv, report.md and the plots (PNG and SVG, the
/// thesis' own values overlaid where it printed them) into the output folder.

#include <filesystem>
#include <string>

namespace hof::app {

struct EvaluationOptions {
  bool quick{false};                       ///< seconds: the smallest liver, few batches (CI)
  std::string only;                        ///< regular expression on cell names; empty: all
  std::filesystem::path out{"out/bench"};  ///< where the report is written
  std::string command_line;                ///< as typed, for the report
};

/// Runs the evaluation. Returns the process exit status: 0, or 1 on bad options or when the
/// report could not be written.
int run_evaluation(const EvaluationOptions& options);

}  // namespace hof::app
