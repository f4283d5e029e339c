#pragma once
/// @file
/// The evaluation plan: every cell of the matrix (its name and description) with the code
/// that measures it, in the report's order. `hof bench --only` filters the plan before any
/// cell runs, so a cell's body is generated only if a chosen cell needs it.

#include <filesystem>
#include <functional>
#include <vector>

#include "hof/app/bench/cell.h"
#include "hof/app/bench/recipes.h"

namespace hof::app::bench {

struct PlannedCell {
  Cell cell;
  std::function<void(Cell&)> run;  ///< fills the cell's figures
};

/// The whole matrix: the thesis' Figures 29–34 re-run (the four livers and the sparse grid;
/// with `quick` the simple liver only, short batches), the haptic rate, several bodies and the
/// coupling schemes. The window cell writes its project under `out`.
[[nodiscard]] std::vector<PlannedCell> plan(bool quick, Bodies& bodies, const std::filesystem::path& out);

}  // namespace hof::app::bench
