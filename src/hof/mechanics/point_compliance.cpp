#include "hof/mechanics/point_compliance.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/vector_kernels.h"
#include "hof/mechanics/forces.h"

namespace hof::mechanics {

bool compute_point_compliance(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                              std::span<const double> weights, Mat3& compliance, int max_iterations) {
  if (model.fixed_dofs.empty() || nodes.size() != weights.size() || !model.needs_matrix) return false;
  detail::SolverWorkspace& w = *state.work;
  // Linearise at the current state (refreshes element rotations), K alone, fixed dofs held.
  compute_forces(model, state, state.x, state.v, w.xt);
  detail::assemble_system(model, state, 0.0, 1.0, detail::AssemblyTarget::kDouble);
  const BlockSparseMatrix& k = w.system;
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    w.block_jacobi[n] = k.block(k.diagonal_slot(static_cast<std::int32_t>(n))).inverse();
  }
  for (int axis = 0; axis < 3; ++axis) {
    // Right-hand side Hᵀ e_axis: the unit force at the point, spread by its weights.
    w.b.setZero();
    for (std::size_t i = 0; i < nodes.size(); ++i) w.b[3 * static_cast<Eigen::Index>(nodes[i]) + axis] += weights[i];
    detail::project(model, w.b);
    const double b_norm = w.b.norm();
    if (!(b_norm > 0.0)) {
      compliance.col(axis).setZero();
      continue;
    }
    // Preconditioned CG on K y = b (K is symmetric positive definite with the fixed dofs held).
    w.dv.setZero();
    w.r = w.b;
    auto precondition = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
      for (std::size_t n = 0; n < model.node_count(); ++n) {
        const Eigen::Index i = 3 * static_cast<Eigen::Index>(n);
        out.segment<3>(i).noalias() = w.block_jacobi[n] * in.segment<3>(i);
      }
    };
    precondition(w.r, w.z);
    w.p = w.z;
    double rho = w.r.dot(w.z);
    bool converged = false;
    for (int it = 0; it < max_iterations; ++it) {
      k.multiply(w.p, w.ap);
      const double curvature = w.p.dot(w.ap);
      if (!(curvature > 0.0)) break;
      const double alpha = rho / curvature;
      w.dv += alpha * w.p;
      w.r -= alpha * w.ap;
      if (w.r.norm() <= 1e-10 * b_norm) {
        converged = true;
        break;
      }
      precondition(w.r, w.z);
      const double rho_next = w.r.dot(w.z);
      w.p = w.z + (rho_next / rho) * w.p;
      rho = rho_next;
    }
    if (!converged || !w.dv.allFinite()) return false;
    Vec3 column = Vec3::Zero();
    for (std::size_t i = 0; i < nodes.size(); ++i)
      column += weights[i] * w.dv.segment<3>(3 * static_cast<Eigen::Index>(nodes[i]));
    compliance.col(axis) = column;
  }
  // The true compliance is symmetric; remove the solver's round-off asymmetry.
  compliance = 0.5 * (compliance + compliance.transpose()).eval();
  return compliance.allFinite();
}

bool system_diagonal_block(const MechanicalModel& model, const MechanicalState& state, std::int32_t node, Mat3& block) {
  if (model.ode.kind != OdeSolverKind::kEulerImplicit || !state.work || node < 0 ||
      static_cast<std::size_t>(node) >= model.node_count())
    return false;
  const detail::SolverWorkspace& w = *state.work;
  if (w.system_assembled_step < 0) return false;
  const std::int64_t slot = w.system.diagonal_slot(node);
  if (detail::uses_single_precision(model)) {
    // The CG then reads (and the assembly may fill) only the single-precision copy.
    const float* values = w.system.single_block(slot);
    for (int q = 0; q < 3; ++q) {
      for (int i = 0; i < 3; ++i)
        block(i, q) = static_cast<double>(values[BlockSparseMatrix::kSingleColumnStride * q + i]);
    }
  } else {
    block = w.system.block(slot);
  }
  return true;
}

}  // namespace hof::mechanics
