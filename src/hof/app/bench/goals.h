#pragma once
/// @file
/// What the measured cells add up to: the springs / co-rotational FEM ratios (the thesis
/// measured springs twice as fast) and the haptic-rate goals with their targets.

#include <cmath>
#include <string>
#include <vector>

#include "hof/app/bench/cell.h"

namespace hof::app::bench {

/// The cell named `name`, or nullptr.
[[nodiscard]] const Cell* find(const std::vector<Cell>& cells, const std::string& name);

struct Ratio {
  std::string settings;
  std::string mesh;
  double force_field{kNaN};  // co-rotational FEM cost / springs cost, forces + assembly
  double step{kNaN};         // whole step: springs steps/s / FEM steps/s
};

/// Per settings and liver where both models ran stably.
[[nodiscard]] std::vector<Ratio> springs_over_fem(const std::vector<Cell>& cells);

struct Goal {
  std::string what;
  std::string unit;
  double target{kNaN};
  double measured{kNaN};
  bool higher_is_better{true};
  [[nodiscard]] bool known() const { return std::isfinite(measured); }
  [[nodiscard]] bool met() const { return known() && (higher_is_better ? measured >= target : measured <= target); }
};

/// The goals that the measured cells speak to (a goal whose cell did not run is left out;
/// one whose cell did not measure stays unknown).
[[nodiscard]] std::vector<Goal> goals(const std::vector<Cell>& cells, const std::vector<Ratio>& ratios);

}  // namespace hof::app::bench
