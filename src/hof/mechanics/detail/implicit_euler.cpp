#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/integrators.h"
#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/detail/vector_kernels.h"

namespace hof::mechanics::detail {

bool implicit_euler_step(const MechanicalModel& model, MechanicalState& state) {
  const double h = model.dt_s;
  const double rk = model.ode.rayleigh_stiffness;
  const double rm = model.ode.rayleigh_mass;
  SolverWorkspace& w = *state.work;

  auto t0 = StageClock::now();
  const double mass_coeff = 1.0 + h * rm, stiffness_coeff = h * (h + rk);
  const bool reuse = w.system_assembled_step >= 0 && state.steps > w.system_assembled_step &&
                     state.steps - w.system_assembled_step < model.ode.matrix_reuse_steps &&
                     w.system_mass_coeff == mass_coeff && w.system_stiffness_coeff == stiffness_coeff;
  if (!reuse) {
    assemble_system(model, state, mass_coeff, stiffness_coeff);
    w.system_assembled_step = state.steps;
    w.system_mass_coeff = mass_coeff;
    w.system_stiffness_coeff = stiffness_coeff;
  }
  state.stats.assembly_s = seconds_since(t0);

  t0 = StageClock::now();
  // Right-hand side without a separate K: with A = (1 + h r_M) M + h (h + r_K) K,
  //   h f − h (h + r_K) K v − h r_M M v  =  h f + M v − A v.
  if (uses_single_precision(model)) {
    const std::size_t nodes = model.node_count();
    parallel_chunks(nodes, 1024, [&](std::size_t b, std::size_t e) {
      BlockSparseMatrix::round_to_single(state.v.data(), w.p_single.data(), b, e);
    });
    w.system.multiply_single(w.p_single.data(), w.ap);
  } else {
    w.system.multiply(state.v, w.ap);
  }
  apply_mass(model, state.v, w.b);
  w.b += h * state.f - w.ap;
  project(model, w.b);
  const bool ok = solve_system(model, state, w.b, w.dv);
  state.v += w.dv;
  project(model, state.v);
  axpy(h, state.v, state.x);
  state.stats.solve_s = seconds_since(t0);
  return ok;
}

}  // namespace hof::mechanics::detail
