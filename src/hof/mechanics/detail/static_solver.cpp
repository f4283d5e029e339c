#include <algorithm>
#include <cmath>

#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/integrators.h"
#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/forces.h"

namespace hof::mechanics::detail {

bool static_step(const MechanicalModel& model, MechanicalState& state) {
  SolverWorkspace& w = *state.work;
  const OdeSolverConfig& cfg = model.ode;
  state.stats.assembly_s = state.stats.solve_s = 0.0;

  auto max_abs = [](const Eigen::VectorXd& f) { return f.size() ? f.cwiseAbs().maxCoeff() : 0.0; };
  double residual = max_abs(state.f);  // step()'s forces at v = 0
  int iteration = 0;
  bool ok = true;
  for (; iteration < cfg.newton_iterations && residual > cfg.newton_residual_tolerance_n; ++iteration) {
    auto t0 = StageClock::now();
    assemble_system(model, state, 0.0, 1.0);
    state.stats.assembly_s += seconds_since(t0);
    t0 = StageClock::now();
    w.b = state.f;
    if (!solve_system(model, state, w.b, w.dv)) {
      ok = false;
      break;
    }
    // Backtracking: halve the correction while the residual grows (co-rotational and
    // hyperelastic tangents are approximate far from equilibrium).
    w.xt = state.x;  // x_saved belongs to step()'s divergence guard
    double step = 1.0;
    double trial = residual;
    for (int halving = 0; halving < 8; ++halving) {
      state.x = w.xt + step * w.dv;
      compute_forces(model, state, state.x, state.v, state.f);
      trial = max_abs(state.f);
      if (trial < residual || !std::isfinite(residual)) break;
      step *= 0.5;
    }
    state.stats.solve_s += seconds_since(t0);
    residual = trial;
    const double correction = step * w.dv.norm();
    if (correction <= cfg.newton_correction_tolerance * std::max(state.x.norm(), 1e-12)) {
      ++iteration;
      break;
    }
  }
  state.stats.newton_iterations = iteration;
  state.stats.residual_force_n = residual;
  return ok && std::isfinite(residual);
}

}  // namespace hof::mechanics::detail
