#pragma once
/// @file
/// Plots of `hof run` and `hof bench` reports: gnuplot scripts rendered to PNG and SVG beside
/// the data they read, collected in plots.gp so that a user can restyle and redraw them.

#include <filesystem>
#include <string>
#include <vector>

namespace hof::app::detail {

/// One figure: its file name (without extension) and the gnuplot commands after the
/// terminal, output, grid, key and title settings (which render_plots writes).
struct Plot {
  std::string name;
  std::string body;
};

/// Text safe inside a gnuplot single-quoted string. A control character (a newline in a body
/// name, written &#10; in the scene) would end the gnuplot command mid-string and lose the
/// plot: it becomes a space.
[[nodiscard]] std::string gnuplot_text(const std::string& text);

/// Renders each plot to NAME.png and NAME.svg in `dir` (960×540; `title` above each unless
/// the plot sets its own), one gnuplot run per file so that a plot with no data does not stop
/// the others, and writes every script into `dir`/plots.gp. Returns the names of the plots
/// whose PNG could not be made (no data, or gnuplot missing).
[[nodiscard]] std::vector<std::string> render_plots(const std::filesystem::path& dir, const std::string& title,
                                                    const std::vector<Plot>& plots);

}  // namespace hof::app::detail
