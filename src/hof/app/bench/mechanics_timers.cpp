#include "hof/app/bench/timers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "hof/haptics/surface_snapshot.h"
#include "hof/mechanics/step.h"

namespace hof::app::bench {

using namespace hof::mechanics;

namespace {

// A step that diverged, or a node more than 1 m from where it started (a liver is 0.2 m: it
// has left the scene even if every number is still finite).
bool checked_step(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& start, Cell& cell) {
  if (!step(model, state)) {
    cell.failure = fmt::format("{}: {}", state.divergence.component, state.divergence.reason);
    return false;
  }
  if ((state.x - start).cwiseAbs().maxCoeff() > 1.0) {
    cell.failure = fmt::format("a node moved more than 1 m at step {}", state.steps);
    return false;
  }
  return true;
}

}  // namespace

void time_cell(const ModelConfig& config, const Budget& budget, Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  if (config.linear.warm_start)
    cell.iterations = config.linear.iterations;  // the haptic-rate CG's depend on the mesh too
  auto model = build_model(config);
  if (!model) {
    cell.stable = false;
    cell.failure = model.error().to_string();
    return;
  }
  cell.nodes = model->node_count();
  MechanicalState state = make_state(*model);
  const Eigen::VectorXd start = state.x;
  std::vector<double> rates;
  double forces = 0, assembly = 0, solve = 0;
  long timed = 0;
  bool ok = checked_step(*model, state, start, cell) && checked_step(*model, state, start, cell);  // warm-up
  for (int b = 0; ok && b < budget.batches; ++b) {
    const auto t0 = Clock::now();
    long n = 0;
    double elapsed = 0.0;
    do {
      ok = checked_step(*model, state, start, cell);
      if (!ok) break;
      forces += state.stats.force_s;
      assembly += state.stats.assembly_s;
      solve += state.stats.solve_s;
      ++n;
      elapsed = seconds_since(t0);
    } while (elapsed < budget.batch_s);
    // A batch cut short by a divergence still tells how fast the steps ran until then.
    if (n > 0 && elapsed > 0.0) rates.push_back(static_cast<double>(n) / elapsed);
    timed += n;
  }
  const auto t_check = Clock::now();
  while (ok && static_cast<double>(state.steps) * model->dt_s < budget.horizon_s &&
         seconds_since(t_check) < budget.stability_wall_s) {
    ok = checked_step(*model, state, start, cell);
  }
  cell.stable = ok;
  cell.stable_over_s = static_cast<double>(ok ? state.steps : std::max<std::int64_t>(state.steps - 1, 0)) * model->dt_s;
  cell.steps = timed;
  if (!rates.empty()) {
    std::sort(rates.begin(), rates.end());
    cell.median = rates[rates.size() / 2];
    cell.min = rates.front();
    cell.max = rates.back();
    cell.measured = true;
  }
  if (timed > 0) {
    const auto n = static_cast<double>(timed);
    cell.forces_us = 1e6 * forces / n;
    cell.assembly_us = 1e6 * assembly / n;
    cell.solve_us = 1e6 * solve / n;
  }
}

// The largest relative error of a step made by `config` (an iterative solve) against an exact
// LDLᵀ solve of the same step from the same state: |Δ − Δ_exact| / |Δ_exact|, Δ the change of
// velocity (dynamic solvers) or of position (static). The inexact model follows its own
// trajectory, so a warm start has its own history; samples are `steps_between_samples` apart.
double step_error(const ModelConfig& config, const Budget& budget) {
  ModelConfig exact_config = config;
  exact_config.linear.kind = LinearSolverKind::kSparseLdlt;
  // The exact side assembles every step: it is stepped once per sample, so a reused matrix
  // would be one from the previous sample's state.
  exact_config.ode.matrix_reuse_steps = 1;
  auto model = build_model(config);
  auto exact = build_model(exact_config);
  if (!model || !exact) return kNaN;
  MechanicalState state = make_state(*model);
  MechanicalState exact_state = make_state(*exact);
  const bool static_solver = config.ode.kind == OdeSolverKind::kStatic;
  double worst = 0.0;
  for (int s = 0; s < budget.error_samples; ++s) {
    // The static solver's steps are Newton iterations towards one equilibrium: the first
    // ones, from rest, are the solves that matter (later ones correct almost nothing).
    const int between = static_solver ? (s == 0 ? 0 : 1) : budget.steps_between_samples;
    for (int i = 0; i < between; ++i) {
      if (!step(*model, state)) return kNaN;
    }
    const Eigen::VectorXd x0 = state.x, v0 = state.v;
    exact_state.x = x0;
    exact_state.v = v0;
    if (!step(*model, state) || !step(*exact, exact_state)) return kNaN;
    const Eigen::VectorXd d = static_solver ? Eigen::VectorXd(state.x - x0) : Eigen::VectorXd(state.v - v0);
    const Eigen::VectorXd d_exact =
        static_solver ? Eigen::VectorXd(exact_state.x - x0) : Eigen::VectorXd(exact_state.v - v0);
    const double scale = d_exact.norm();
    if (!(scale > 0.0)) continue;
    worst = std::max(worst, (d - d_exact).norm() / scale);
  }
  return worst;
}

// One haptic tick per device reading, as the haptic loop makes it: the device slides along
// a loop over the liver's top, 3 mm under the surface (a contact every tick), the surface at
// rest (the thesis' useBoundTree test, l. 1221). Each tick is timed alone: p50/p99/max.
void time_renderer(const mesh::TriMesh& surface, haptics::RendererKind kind, bool bound_tree, const Budget& budget,
                   Cell& cell) {
  collision::AabbTreeOptions tree;
  tree.use_bound_tree = bound_tree;
  const haptics::SurfaceSnapshot snapshot = haptics::make_snapshot(surface, tree);
  Vec3 lo = surface.vertices.front(), hi = lo;
  for (const Vec3& p : surface.vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  auto top = [&](double x, double y) {
    const collision::SweepHit hit =
        snapshot.tree.first_hit_segment(snapshot.view(), Vec3(x, y, hi.z() + 1.0), Vec3(x, y, lo.z() - 1.0));
    return hit.triangle >= 0 ? std::optional<double>(hit.point.z()) : std::nullopt;
  };
  constexpr int kPath = 2000;
  std::vector<Vec3> path;
  path.reserve(kPath);
  for (int i = 0; i < kPath; ++i) {
    const double a = 2 * std::numbers::pi * i / kPath;
    const double x = centre.x() + 0.4 * half.x() * std::cos(a), y = centre.y() + 0.4 * half.y() * std::sin(a);
    if (auto z = top(x, y)) path.emplace_back(x, y, *z - 0.003);
  }
  if (path.empty()) {
    cell.stable = false;
    cell.failure = "no point of the surface under the device's path";
    return;
  }
  haptics::RendererConfig config;
  config.kind = kind;
  haptics::SurfaceMaterial material;
  material.stiffness = 1.0;
  haptics::HapticRenderer renderer(config, material, 1000.0);
  renderer.reset(path[0] + Vec3(0, 0, 0.02));  // from above, as a hand arrives
  std::vector<double> ticks;
  ticks.reserve(1 << 20);
  std::size_t contacts = 0;
  const auto t_start = Clock::now();
  const double total_s = budget.batches * budget.batch_s;
  for (std::size_t i = 0; ticks.size() < ticks.capacity() && seconds_since(t_start) < total_s; ++i) {
    const auto t0 = Clock::now();
    const haptics::ContactState& c = renderer.update(path[i % path.size()], Vec3::Zero(), snapshot, false, 1e-3);
    const auto t1 = Clock::now();
    contacts += c.in_contact ? 1 : 0;
    ticks.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  std::sort(ticks.begin(), ticks.end());
  auto quantile = [&](double q) { return ticks[static_cast<std::size_t>(q * static_cast<double>(ticks.size() - 1))]; };
  cell.steps = static_cast<long>(ticks.size());
  cell.tick_p50_us = quantile(0.5);
  cell.tick_p99_us = quantile(0.99);
  cell.tick_max_us = ticks.back();
  cell.contact_fraction = static_cast<double>(contacts) / static_cast<double>(ticks.size());
  cell.measured = true;
}

}  // namespace hof::app::bench
