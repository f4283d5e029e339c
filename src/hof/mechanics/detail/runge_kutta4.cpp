#include "hof/mechanics/detail/integrators.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/detail/vector_kernels.h"
#include "hof/mechanics/forces.h"

namespace hof::mechanics::detail {

bool runge_kutta4_step(const MechanicalModel& model, MechanicalState& state) {
  const double h = model.dt_s;
  SolverWorkspace& w = *state.work;
  const auto t0 = StageClock::now();
  // Stage k: kx = v_stage, kv = M⁻¹ f(x_stage, v_stage). Stage 1's forces are step()'s.
  auto derivatives = [&](const Eigen::VectorXd& vs, Eigen::VectorXd& kx, Eigen::VectorXd& kv) {
    kx = vs;
    project(model, kx);
    apply_inverse_mass(model, state.f, kv);
  };
  auto stage = [&](const Eigen::VectorXd& xs, const Eigen::VectorXd& vs, Eigen::VectorXd& kx, Eigen::VectorXd& kv) {
    compute_forces(model, state, xs, vs, state.f);
    derivatives(vs, kx, kv);
  };
  derivatives(state.v, w.k1x, w.k1v);
  w.xt = state.x + 0.5 * h * w.k1x;
  w.vt = state.v + 0.5 * h * w.k1v;
  stage(w.xt, w.vt, w.k2x, w.k2v);
  w.xt = state.x + 0.5 * h * w.k2x;
  w.vt = state.v + 0.5 * h * w.k2v;
  stage(w.xt, w.vt, w.k3x, w.k3v);
  w.xt = state.x + h * w.k3x;
  w.vt = state.v + h * w.k3v;
  stage(w.xt, w.vt, w.k4x, w.k4v);
  state.x += (h / 6.0) * (w.k1x + 2.0 * w.k2x + 2.0 * w.k3x + w.k4x);
  state.v += (h / 6.0) * (w.k1v + 2.0 * w.k2v + 2.0 * w.k3v + w.k4v);
  // RK4 is force evaluations: the whole step counts as force time, as it always has.
  state.stats.force_s += seconds_since(t0);
  state.stats.solve_s = 0.0;
  return true;
}

}  // namespace hof::mechanics::detail
