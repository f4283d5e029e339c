#pragma once
/// @file
/// The evaluation's report: the Markdown tables (printed on stdout and in report.md),
/// results.json, results.csv and report.md itself. Field names, units and column orders are
/// what scripts reading a report rely on: change them only on purpose.

#include <string>
#include <vector>

#include "hof/app/bench/cell.h"
#include "hof/app/bench/goals.h"
#include "hof/app/detail/plots.h"

namespace hof::app::bench {

/// How the run was made, as the report states it.
struct RunInfo {
  std::string command_line;
  std::string date;     ///< UTC
  std::string machine;  ///< machine_description()
  bool quick{false};
  std::string only;
  double seconds{0.0};  ///< wall time of all cells
};

/// The CPU, its hardware threads and the kernel.
[[nodiscard]] std::string machine_description();

/// The Markdown tables, one section per kind of cell that ran, then the ratios and goals.
[[nodiscard]] std::string tables(const std::vector<Cell>& cells, const std::vector<Ratio>& ratios,
                                 const std::vector<Goal>& goal_list);

/// results.json's text (indented, with a final newline).
[[nodiscard]] std::string results_json(const RunInfo& run, const std::vector<Cell>& cells,
                                       const std::vector<Ratio>& ratios, const std::vector<Goal>& goal_list);

/// results.csv's text: one row per cell.
[[nodiscard]] std::string csv(const std::vector<Cell>& cells);

/// report.md: how the run was made, the tables, the plots that were made (those in `failed`
/// are left out), what this version does not measure.
[[nodiscard]] std::string report_markdown(const RunInfo& run, const std::string& table_text,
                                          const std::vector<detail::Plot>& plots,
                                          const std::vector<std::string>& failed);

}  // namespace hof::app::bench
