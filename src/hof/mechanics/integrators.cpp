#include "hof/mechanics/integrators.h"

#include <chrono>
#include <cmath>

#include "hof/mechanics/assembly.h"
#include "hof/mechanics/forces.h"
#include "hof/mechanics/linear_solve.h"
#include "hof/mechanics/parallel.h"
#include "hof/mechanics/vector_kernels.h"

namespace hof::mechanics::detail {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// out = M⁻¹ in (lumped mass), fixed nodes zero.
void apply_inverse_mass(const MechanicalModel& model, const Eigen::VectorXd& in, Eigen::VectorXd& out) {
  const std::size_t n = model.node_count();
  parallel_chunks(n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
      const double inverse_mass = 1.0 / model.node_mass_kg[i];
      for (Eigen::Index a = 0; a < 3; ++a) out[k + a] = model.fixed_dof_mask[static_cast<std::size_t>(k + a)] ? 0.0 : inverse_mass * in[k + a];
    }
  });
}

// out = M in (lumped mass).
void apply_mass(const MechanicalModel& model, const Eigen::VectorXd& in, Eigen::VectorXd& out) {
  const std::size_t n = model.node_count();
  parallel_chunks(n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
      out.segment<3>(k) = model.node_mass_kg[i] * in.segment<3>(k);
    }
  });
}

}  // namespace

bool explicit_euler_step(const MechanicalModel& model, MechanicalState& state) {
  const double h = model.dt_s;
  SolverWorkspace& w = state.work;
  auto t0 = Clock::now();
  compute_forces(model, state, state.x, state.v, state.f);
  state.stats.force_s = seconds_since(t0);
  t0 = Clock::now();
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

bool runge_kutta4_step(const MechanicalModel& model, MechanicalState& state) {
  const double h = model.dt_s;
  SolverWorkspace& w = state.work;
  auto t0 = Clock::now();
  // Stage k: kx = v_stage, kv = M⁻¹ f(x_stage, v_stage).
  auto stage = [&](const Eigen::VectorXd& xs, const Eigen::VectorXd& vs, Eigen::VectorXd& kx, Eigen::VectorXd& kv) {
    compute_forces(model, state, xs, vs, state.f);
    kx = vs;
    project(model, kx);
    apply_inverse_mass(model, state.f, kv);
  };
  stage(state.x, state.v, w.k1x, w.k1v);
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
  state.stats.force_s = seconds_since(t0);
  state.stats.solve_s = 0.0;
  return true;
}

bool implicit_euler_step(const MechanicalModel& model, MechanicalState& state) {
  const double h = model.dt_s;
  const double rk = model.ode.rayleigh_stiffness;
  const double rm = model.ode.rayleigh_mass;
  SolverWorkspace& w = state.work;

  auto t0 = Clock::now();
  compute_forces(model, state, state.x, state.v, state.f);
  state.stats.force_s = seconds_since(t0);

  t0 = Clock::now();
  const double mass_coeff = 1.0 + h * rm, stiffness_coeff = h * (h + rk);
  const bool reuse = w.system_assembled_step >= 0 && state.steps > w.system_assembled_step &&
                     state.steps - w.system_assembled_step < model.ode.matrix_reuse_steps && w.system_mass_coeff == mass_coeff &&
                     w.system_stiffness_coeff == stiffness_coeff;
  if (!reuse) {
    assemble_system(model, state, mass_coeff, stiffness_coeff);
    w.system_assembled_step = state.steps;
    w.system_mass_coeff = mass_coeff;
    w.system_stiffness_coeff = stiffness_coeff;
  }
  state.stats.assembly_s = seconds_since(t0);

  t0 = Clock::now();
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

bool static_step(const MechanicalModel& model, MechanicalState& state) {
  SolverWorkspace& w = state.work;
  const OdeSolverConfig& cfg = model.ode;
  state.v.setZero();
  state.stats.force_s = state.stats.assembly_s = state.stats.solve_s = 0.0;

  auto max_abs = [](const Eigen::VectorXd& f) { return f.size() ? f.cwiseAbs().maxCoeff() : 0.0; };
  auto t0 = Clock::now();
  compute_forces(model, state, state.x, state.v, state.f);
  state.stats.force_s += seconds_since(t0);
  double residual = max_abs(state.f);
  int iteration = 0;
  bool ok = true;
  for (; iteration < cfg.newton_iterations && residual > cfg.newton_residual_tolerance_n; ++iteration) {
    t0 = Clock::now();
    assemble_system(model, state, 0.0, 1.0);
    state.stats.assembly_s += seconds_since(t0);
    t0 = Clock::now();
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
