#include "hof/app/evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <regex>
#include <vector>

#include "hof/app/bench/goals.h"
#include "hof/app/bench/plan.h"
#include "hof/app/bench/plots.h"
#include "hof/app/bench/report.h"
#include "hof/app/detail/cli_failure.h"
#include "hof/app/detail/plots.h"
#include "hof/core/file_write.h"
#include "hof/core/progress.h"

namespace hof::app {

int run_evaluation(const EvaluationOptions& options) {
  std::regex only;
  try {
    only = std::regex(options.only.empty() ? std::string(".") : options.only);
  } catch (const std::regex_error& e) {
    return detail::fail(fmt::format("--only '{}': not a regular expression ({})", options.only, e.what()));
  }
  std::error_code ec;
  std::filesystem::create_directories(options.out, ec);
  if (ec)
    return detail::fail(fmt::format("{}: cannot create the report folder: {}", options.out.string(), ec.message()));

  bench::Bodies bodies;
  std::vector<bench::PlannedCell> planned;
  for (bench::PlannedCell& p : bench::plan(options.quick, bodies, options.out)) {
    if (std::regex_search(p.cell.name, only)) planned.push_back(std::move(p));
  }
  if (planned.empty())
    return detail::fail(
        fmt::format("--only '{}' matches no cell (names look like force_fields/thesis/medium/springs)", options.only));

  const ProgressSink progress = make_terminal_progress(false);
  const auto started = bench::Clock::now();
  std::vector<bench::Cell> cells;
  for (std::size_t i = 0; i < planned.size(); ++i) {
    progress(fmt::format("hof bench: {} ({}/{})", planned[i].cell.name, i + 1, planned.size()),
             static_cast<double>(i) / static_cast<double>(planned.size()));
    bench::Cell cell = planned[i].cell;
    planned[i].run(cell);
    cells.push_back(std::move(cell));
  }
  progress("hof bench: done", 1.0);
  const double total_s = bench::seconds_since(started);

  const std::vector<bench::Ratio> ratios = bench::springs_over_fem(cells);
  const std::vector<bench::Goal> goal_list = bench::goals(cells, ratios);
  const std::string table_text = bench::tables(cells, ratios, goal_list);
  std::fputs(table_text.c_str(), stdout);

  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const bench::RunInfo info{options.command_line, date,         bench::machine_description(),
                            options.quick,        options.only, total_s};

  const std::vector<detail::Plot> plots = bench::write_plot_data(options.out, cells, ratios);
  const std::vector<std::string> failed = detail::render_plots(options.out, "", plots);

  const std::string report = bench::report_markdown(info, table_text, plots, failed);

  std::string write_errors;
  for (const auto& [file, text] : {std::pair{"results.json", bench::results_json(info, cells, ratios, goal_list)},
                                   std::pair{"results.csv", bench::csv(cells)}, std::pair{"report.md", report}}) {
    if (auto w = write_file_atomically(options.out / file, text); !w) write_errors += w.error().to_string() + "\n";
  }
  if (!write_errors.empty()) return detail::fail("the report could not be written:\n" + write_errors);
  if (!failed.empty()) {
    std::string names;
    for (const std::string& f : failed) names += (names.empty() ? "" : ", ") + f;
    std::fprintf(stderr, "hof: note: no plot for %s (gnuplot missing?); plots.gp is in %s\n", names.c_str(),
                 options.out.c_str());
  }
  std::fprintf(stderr, "hof bench: %zu cells in %.0f s; report in %s/report.md\n", cells.size(), total_s,
               options.out.c_str());
  return 0;
}

}  // namespace hof::app
