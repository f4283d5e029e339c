#pragma once
/// @file
/// The evaluation's plots: one .dat per figure (the thesis' Figures 29–34, the threads, the
/// renderers, the haptic rate, the coupling schemes) written beside the gnuplot script that
/// draws it; `?` where a cell was not measured.

#include <filesystem>
#include <vector>

#include "hof/app/bench/cell.h"
#include "hof/app/bench/goals.h"
#include "hof/app/detail/plots.h"

namespace hof::app::bench {

/// Writes the data files into `dir` and returns the plots to render (a figure none of whose
/// cells ran is left out).
[[nodiscard]] std::vector<detail::Plot> write_plot_data(const std::filesystem::path& dir,
                                                        const std::vector<Cell>& cells,
                                                        const std::vector<Ratio>& ratios);

}  // namespace hof::app::bench
