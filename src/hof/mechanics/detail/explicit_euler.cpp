#include "hof/mechanics/detail/integrators.h"
#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/detail/vector_kernels.h"

namespace hof::mechanics::detail {

void apply_inverse_mass(const MechanicalModel& model, const Eigen::VectorXd& in, Eigen::VectorXd& out) {
  const std::size_t n = model.node_count();
  parallel_chunks(n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
      const double inverse_mass = 1.0 / model.node_mass_kg[i];
      for (Eigen::Index a = 0; a < 3; ++a)
        out[k + a] = model.fixed_dof_mask[static_cast<std::size_t>(k + a)] ? 0.0 : inverse_mass * in[k + a];
    }
  });
}

void apply_mass(const MechanicalModel& model, const Eigen::VectorXd& in, Eigen::VectorXd& out) {
  const std::size_t n = model.node_count();
  parallel_chunks(n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
      out.segment<3>(k) = model.node_mass_kg[i] * in.segment<3>(k);
    }
  });
}

bool explicit_euler_step(const MechanicalModel& model, MechanicalState& state) {
  const double h = model.dt_s;
  SolverWorkspace& w = *state.work;
  const auto t0 = StageClock::now();
  apply_inverse_mass(model, state.f, w.dv);  // acceleration
  if (model.ode.symplectic) {
    axpy(h, w.dv, state.v);
    axpy(h, state.v, state.x);
  } else {
    axpy(h, state.v, state.x);
    axpy(h, w.dv, state.v);
  }
  state.stats.solve_s = seconds_since(t0);
  return true;
}

}  // namespace hof::mechanics::detail
