#include "hof/mechanics/linear_system.h"

#include <cmath>

#include "hof/mechanics/parallel.h"

namespace hof::mechanics::detail {

namespace {
constexpr std::size_t kVectorChunk = 4096;
}

double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b, std::vector<double>& partials) {
  const double* pa = a.data();
  const double* pb = b.data();
  return deterministic_sum(static_cast<std::size_t>(a.size()), kVectorChunk, partials,
                           [&](std::size_t begin, std::size_t end) {
                             double s = 0.0;
                             for (std::size_t i = begin; i < end; ++i) s += pa[i] * pb[i];
                             return s;
                           });
}

void axpy(double alpha, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  const double* px = x.data();
  double* py = y.data();
  parallel_chunks(static_cast<std::size_t>(x.size()), kVectorChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) py[i] += alpha * px[i];
  });
}

void project(const MechanicalModel& model, Eigen::VectorXd& vector) {
  for (std::int32_t d : model.fixed_dofs) vector[d] = 0.0;
}

void assemble_system(const MechanicalModel& model, MechanicalState& state, double mass_coeff, double stiffness_coeff) {
  BlockSparseMatrix& a = state.work.system;
  a.set_zero();
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    if (model.force_fields[k]->has_stiffness()) {
      model.force_fields[k]->add_stiffness(state.field_states[k], stiffness_coeff, a);
    }
  }
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    a.block(a.diagonal_slot(static_cast<std::int32_t>(n))).diagonal().array() += mass_coeff * model.node_mass_kg[n];
  }
  // Fixed degrees of freedom: identity rows and columns (projection P A P + (I − P)).
  const auto& row_start = a.row_start();
  const auto& columns = a.columns();
  for (std::int32_t d : model.fixed_dofs) {
    const std::int32_t n = d / 3;
    const int axis = d % 3;
    for (std::int64_t s = row_start[n]; s < row_start[n + 1]; ++s) {
      a.block(s).row(axis).setZero();
      a.block(a.slot(columns[s], n)).col(axis).setZero();
    }
    a.block(a.diagonal_slot(n))(axis, axis) = 1.0;
  }
}

void prepare_linear_solver(const MechanicalModel& model, MechanicalState& state) {
  SolverWorkspace& w = state.work;
  if (model.needs_matrix) w.system.update_single_precision();  // sizes the copy once
  if (model.linear.kind != LinearSolverKind::kSparseLdlt || !model.needs_matrix) return;
  // CSC copy of the block matrix. Each triplet carries its block-storage index + 1 as its
  // value, which gives the map from CSC storage back to block storage after compression.
  const BlockSparseMatrix& a = w.system;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(a.block_count()) * 9);
  for (std::int32_t r = 0; r < a.block_rows(); ++r) {
    for (std::int64_t s = a.row_start()[r]; s < a.row_start()[r + 1]; ++s) {
      const std::int32_t c = a.columns()[s];
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          triplets.emplace_back(3 * r + i, 3 * c + j, static_cast<double>(BlockSparseMatrix::value_index(s, i, j) + 1));
        }
      }
    }
  }
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(a.block_rows());
  w.csc.resize(n, n);
  w.csc.setFromTriplets(triplets.begin(), triplets.end());
  w.csc.makeCompressed();
  w.csc_from_block.resize(static_cast<std::size_t>(w.csc.nonZeros()));
  for (Eigen::Index k = 0; k < w.csc.nonZeros(); ++k) {
    w.csc_from_block[static_cast<std::size_t>(k)] = static_cast<std::int64_t>(w.csc.valuePtr()[k]) - 1;
  }
  w.ldlt = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>();
  w.ldlt->analyzePattern(w.csc);
}

namespace {

bool solve_ldlt(MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  SolverWorkspace& w = state.work;
  const double* block_values = w.system.values();
  double* csc_values = w.csc.valuePtr();
  for (std::size_t k = 0; k < w.csc_from_block.size(); ++k) csc_values[k] = block_values[w.csc_from_block[k]];
  w.ldlt->factorize(w.csc);
  if (w.ldlt->info() != Eigen::Success) return false;
  x = w.ldlt->solve(b);
  state.stats.linear_iterations = 1;
  state.stats.linear_residual = 0.0;
  return x.allFinite();
}

// Conjugate gradients with SOFA's CGLinearSolver stopping rules: stop when |r|²/|b|² falls
// below `tolerance`, or when the curvature pᵀAp falls below `threshold`, or after
// `iterations`. Optional block-Jacobi preconditioning (inverse 3x3 diagonal blocks).
bool solve_cg(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  SolverWorkspace& w = state.work;
  const LinearSolverConfig& cfg = model.linear;
  BlockSparseMatrix& a = w.system;
  const bool precondition = cfg.block_jacobi;
  if (cfg.mixed_precision) a.update_single_precision();
  const std::size_t nodes = model.node_count();

  if (precondition) {
    for (std::size_t n = 0; n < nodes; ++n) {
      w.block_jacobi[n] = a.block(a.diagonal_slot(static_cast<std::int32_t>(n))).inverse();
    }
  }
  auto apply_preconditioner = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    parallel_chunks(nodes, 512, [&](std::size_t n0, std::size_t n1) {
      for (std::size_t n = n0; n < n1; ++n) {
        const Eigen::Index i = 3 * static_cast<Eigen::Index>(n);
        out.segment<3>(i).noalias() = w.block_jacobi[n] * in.segment<3>(i);
      }
    });
  };

  x.setZero();
  w.r = b;
  const double b_norm2 = dot(b, b, w.partials);
  state.stats.linear_iterations = 0;
  state.stats.linear_residual = 0.0;
  if (!(b_norm2 > 0.0)) return std::isfinite(b_norm2);
  if (precondition) apply_preconditioner(w.r, w.z);
  const Eigen::VectorXd& z = precondition ? w.z : w.r;
  w.p = z;
  double rho = dot(w.r, z, w.partials);
  double r_norm2 = b_norm2;
  double first_curvature = 0.0;
  int iteration = 0;
  for (; iteration < cfg.iterations; ++iteration) {
    if (r_norm2 / b_norm2 <= cfg.tolerance) break;
    if (cfg.mixed_precision) a.multiply_single(w.p, w.ap);
    else a.multiply(w.p, w.ap);
    const double curvature = dot(w.p, w.ap, w.partials);
    // SOFA compares pᵀAp with `threshold` in absolute terms, which in its unit-free scenes
    // means "the denominator vanished". In SI units (kg, m) pᵀAp is legitimately tiny, so
    // the same intent is kept scale-free: relative to the first iteration's curvature.
    if (iteration == 0) first_curvature = std::abs(curvature);
    if (!(std::abs(curvature) > cfg.threshold * first_curvature) || !(first_curvature > 0.0)) break;
    const double alpha = rho / curvature;
    axpy(alpha, w.p, x);
    axpy(-alpha, w.ap, w.r);
    if (precondition) apply_preconditioner(w.r, w.z);
    const double rho_next = dot(w.r, z, w.partials);
    r_norm2 = precondition ? dot(w.r, w.r, w.partials) : rho_next;
    const double beta = rho_next / rho;
    rho = rho_next;
    // p = z + beta p
    const double* pz = z.data();
    double* pp = w.p.data();
    parallel_chunks(static_cast<std::size_t>(w.p.size()), kVectorChunk, [&](std::size_t i0, std::size_t i1) {
      for (std::size_t i = i0; i < i1; ++i) pp[i] = pz[i] + beta * pp[i];
    });
  }
  state.stats.linear_iterations = iteration;
  state.stats.linear_residual = r_norm2 / b_norm2;
  return std::isfinite(r_norm2);
}

}  // namespace

bool solve_system(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  if (model.linear.kind == LinearSolverKind::kSparseLdlt) return solve_ldlt(state, b, x);
  return solve_cg(model, state, b, x);
}

}  // namespace hof::mechanics::detail
