#pragma once
/// @file
/// The bench's timers: each measures one kind of cell and fills its figures. The mechanics
/// alone (steps/s in batches, stability, the error against an exact solve), a haptic tick,
/// and whole sessions (real time, the window, several bodies, the coupling schemes).

#include <cstdint>
#include <filesystem>
#include <vector>

#include "hof/app/bench/cell.h"
#include "hof/app/bench/recipes.h"
#include "hof/haptics/haptic_renderer.h"
#include "hof/mesh/boundary.h"

namespace hof::app::bench {

/// Steps the model in `budget.batches` batches (steps/s min/median/max, the split per step),
/// then checks that it stays stable over `budget.horizon_s` of simulated time.
void time_cell(const mechanics::ModelConfig& config, const Budget& budget, Cell& cell);

/// The largest relative error of a step made by `config` (an iterative solve) against an exact
/// LDLᵀ solve of the same step from the same state. NaN when a step failed.
[[nodiscard]] double step_error(const mechanics::ModelConfig& config, const Budget& budget);

/// The cost of one haptic tick of `kind` sliding 3 mm under the surface at rest.
void time_renderer(const mesh::TriMesh& surface, haptics::RendererKind kind, bool bound_tree, const Budget& budget,
                   Cell& cell);

/// The whole framework in real time: a scripted hand pressing the liver's top.
void time_framework(const Body& b, const mechanics::ModelConfig& config, coupling::ContactCoupling mode, double seconds,
                    Cell& cell);

/// time_framework's haptic-rate press with the window open (needs a display), written as a
/// project into `dir`/window.
void time_framework_window(const Body& b, const mechanics::ModelConfig& config, const std::filesystem::path& dir,
                           double seconds, Cell& cell);

/// `count` livers side by side, the first pressed, in virtual time.
void time_bodies(const Body& b, const mechanics::ModelConfig& config, int count, double seconds, Cell& cell);

/// The static FEM reaction of the pressed node held at 1, 2, 3 and 4 mm (the coupling cells'
/// reference).
struct CouplingReference {
  std::int32_t node{-1};
  Vec3 top{Vec3::Zero()};
  std::vector<double> depths;
  std::vector<Vec3> reactions;
};

[[nodiscard]] Expected<CouplingReference> coupling_reference(const Body& b);

/// The felt force of a coupling scheme against `ref`, and its cost.
void time_coupling(const Body& b, const CouplingReference& ref, coupling::ContactCoupling mode, Cell& cell);

}  // namespace hof::app::bench
