#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/integrators.h"
#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/detail/vector_kernels.h"

#include <span>

namespace hof::mechanics::detail {

namespace {

// Adds `sign`·coeff·block to the diagonal blocks of A (its single-precision copy when the CG
// reads that one), rows and columns of held dofs left as the projection made them.
void add_node_stiffness(const MechanicalModel& model, BlockSparseMatrix& a, std::span<const NodeStiffness> entries,
                        double coeff, bool single) {
  for (const NodeStiffness& e : entries) {
    if (e.node < 0 || static_cast<std::size_t>(e.node) >= model.node_count()) continue;
    Mat3 block = coeff * e.block;
    for (int q = 0; q < 3; ++q) {
      if (model.fixed_dof_mask[3 * static_cast<std::size_t>(e.node) + static_cast<std::size_t>(q)]) {
        block.row(q).setZero();
        block.col(q).setZero();
      }
    }
    const std::int64_t slot = a.diagonal_slot(e.node);
    if (single) {
      float* values = a.single_block(slot);
      for (int q = 0; q < 3; ++q) {
        for (int i = 0; i < 3; ++i)
          values[BlockSparseMatrix::kSingleColumnStride * q + i] += static_cast<float>(block(i, q));
      }
    } else {
      a.block(slot) += block;
    }
  }
}

// The external stiffness (contact springs) into A: this step's entries in, and, when the
// matrix is reused, the ones of the step that last put some in taken out first. The blocks
// sit on diagonal blocks only, so A's pattern (and the direct solver's analysis) is unchanged.
// Nothing is done without entries: A is then bit for bit the model's own.
void apply_external_stiffness(const MechanicalModel& model, MechanicalState& state, bool reused,
                              double stiffness_coeff) {
  SolverWorkspace& w = *state.work;
  const bool single = uses_single_precision(model);
  if (reused && !w.external_stiffness_applied.empty()) {
    add_node_stiffness(model, w.system, w.external_stiffness_applied, -w.external_stiffness_coeff, single);
  }
  const bool changed = !w.external_stiffness_applied.empty() || !state.external_stiffness.empty();
  // Grows only when a step has more entries than any before it (no allocation otherwise).
  w.external_stiffness_applied.assign(state.external_stiffness.begin(), state.external_stiffness.end());
  w.external_stiffness_coeff = stiffness_coeff;
  add_node_stiffness(model, w.system, state.external_stiffness, stiffness_coeff, single);
  // A changed diagonal: the CG's Jacobi part is taken again.
  if (changed) ++w.system_assemblies;
}

}  // namespace

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
  apply_external_stiffness(model, state, reuse, stiffness_coeff);
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
