#pragma once
/// @file
/// One cell of `hof bench`'s evaluation matrix (what was measured and how it went) and the
/// measuring budget every timer keeps to. Shared by the plan, the timers, the goals and the
/// report.

#include <chrono>
#include <cstddef>
#include <limits>
#include <string>

namespace hof::app::bench {

using Clock = std::chrono::steady_clock;

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[nodiscard]] inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// How long each cell is measured. Full: five batches of at least 0.2 s (the median of five
// is robust to one descheduled batch on a loaded machine), stability over 1 s of simulated
// time (the thesis' runs went on until the liver rested, l. 1260), three error samples.
struct Budget {
  int batches;
  double batch_s;
  double horizon_s;         // simulated time a cell must survive to count as stable
  double stability_wall_s;  // ... unless checking it would take longer than this
  int error_samples;
  int steps_between_samples;
};

[[nodiscard]] inline Budget budget_for(bool quick) {
  return quick ? Budget{3, 0.02, 0.1, 0.3, 2, 5} : Budget{5, 0.2, 1.0, 4.0, 3, 10};
}

// One measurement of the matrix. Fields that do not apply stay NaN / empty.
struct Cell {
  std::string section, name;
  std::string mesh, field, settings, solver;
  double dt_s{kNaN};
  int iterations{0};
  bool warm_start{false};
  bool coarse_correction{false};  // the CG's two-level preconditioner
  int matrix_reuse{1};            // implicit Euler: steps one assembled matrix serves
  int threads{0};
  std::size_t nodes{0}, elements{0}, triangles{0};
  double median{kNaN}, min{kNaN}, max{kNaN};  // steps/s
  long steps{0};
  bool measured{false};
  bool stable{true};
  double stable_over_s{0.0};  // simulated time it ran without diverging
  std::string failure;
  double step_error{kNaN};  // relative, against an exact LDLᵀ solve of the same step
  double forces_us{kNaN}, assembly_us{kNaN}, solve_us{kNaN};
  // Haptic renderers: the cost of one tick (µs) and the share of ticks in contact.
  std::string renderer;
  bool bound_tree{true};
  double tick_p50_us{kNaN}, tick_p99_us{kNaN}, tick_max_us{kNaN};
  double contact_fraction{kNaN};
  // The whole framework in real time: the simulation's rates in the thesis' three states
  // (steps/s of wall time), and how much simulated time the wall time held.
  double rate_untouched{kNaN}, rate_deforming{kNaN}, rate_contact{kNaN};
  double simulated_s{kNaN}, wall_s{kNaN};
  double frames_per_s{kNaN};  // with the window open
  int bodies{0};              // livers in the world
  // Coupling schemes: the felt force's largest relative error against the static FEM
  // reaction over the press's depths.
  double force_error{kNaN};
  double force_error_settled{kNaN};  // at the deepest point, after the hold
};

}  // namespace hof::app::bench
