#pragma once
/// @file
/// The solver's workspace of a MechanicalState: everything the integrators and the linear
/// solvers need between and within steps that is not a physical quantity — scratch vectors
/// sized once (so a step never allocates), the system matrix, the sparse direct solver's
/// factorisation, the CG's coarse space and thread plan, and the task arena.

#include <tbb/task_arena.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

#include "hof/mechanics/block_sparse_matrix.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// The sparse direct solver's state (CHOLMOD's factors and workspace, linear_solve.cpp): kept
/// out of this header so that HoF's headers do not need SuiteSparse's.
struct DirectSolver;
struct DirectSolverDeleter {
  void operator()(DirectSolver* solver) const noexcept;
};

/// The coarse space of the CG's two-level preconditioner (coarse_correction.h): sized when
/// the state is made, formed and factored every few steps.
struct CoarseSpace {
  std::int32_t aggregates{0};           // 0: no coarse space
  std::vector<std::int32_t> aggregate;  // (N) aggregate of each node
  std::vector<Eigen::Vector3d> arm;     // (N) node minus its aggregate's centre, over the aggregate's size
  std::vector<Eigen::Vector3d> centre;  // (aggregates) scratch for the centres
  std::vector<double> size;             // (aggregates) half the largest extent of each aggregate
  std::vector<std::int32_t> members;    // (aggregates) scratch for the node counts
  Eigen::MatrixXd matrix;               // (6G × 6G) Pᵀ A P
  Eigen::LLT<Eigen::MatrixXd> factor;   // its Cholesky factor
  Eigen::VectorXd solution;             // (6G) Pᵀ r, then the coarse solution
  std::vector<double> partials;         // (CG chunks × 6G) each chunk's Pᵀ r, added in chunk order
  std::int64_t built_step{-1};          // the step whose matrix and positions formed it (−1: none)
  bool usable{false};                   // the last factorisation succeeded
};

/// Solver scratch, sized by make_state() (size_workspace, workspace_setup.h).
struct SolverWorkspace {
  std::unique_ptr<tbb::task_arena> arena;  // limits the threads this model uses
  Eigen::VectorXd b, dv, r, p, z, ap, az,
      diag_inv;                      // CG and implicit Euler (3N); diag_inv: 1 / A's diagonal (two-level CG)
  Eigen::VectorXd cg_previous;       // (3N) the last CG solution: a warm start's guess
  Eigen::VectorXd x_saved, v_saved;  // last good state, restored on divergence
  Eigen::VectorXd k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v, xt, vt;  // RK4
  std::vector<float, Eigen::aligned_allocator<float>> p_single;  // CG direction rounded, 4 per node (+ exchange copies)
  std::vector<double> partials;                                  // deterministic reductions
  // The CG's exchange between threads (see solve_cg): the entries of the direction that a
  // thread's rows read from other threads' nodes are also copied to a compact block of
  // p_single after the first N+1 nodes, and the product reads them there.
  std::size_t cg_parts{1};                    // threads the CG's chunks are split over
  std::vector<std::int32_t> cg_pair_columns;  // the single copy's pair columns, redirected (empty: no exchange)
  std::vector<std::int32_t> cg_send_start;    // (CG chunks+1) each chunk's range in cg_send_from/to
  std::vector<std::int32_t> cg_send_from, cg_send_to;  // node of the chunk, node index of its copy
  BlockSparseMatrix system;                            // A = αM + βK, values refilled each step
  // The step at which implicit Euler assembled `system` for itself with these coefficients
  // (−1: it holds something else, e.g. the compliance's K): what matrix reuse may reuse.
  std::int64_t system_assembled_step{-1};
  std::uint64_t system_assemblies{0};  // counts assemble_system's fills of `system`
  std::uint64_t diag_inv_assembly{0};  // the fill diag_inv was taken from (0: none)
  double system_mass_coeff{0.0}, system_stiffness_coeff{0.0};
  // The external stiffness (MechanicalState::external_stiffness) that `system` holds now, times
  // the coefficient it was added with: a reused matrix takes it out again before the step's own.
  std::vector<NodeStiffness> external_stiffness_applied;
  double external_stiffness_coeff{0.0};
  std::vector<Eigen::Matrix3d> block_jacobi;  // (N) inverse diagonal blocks
  CoarseSpace coarse;                         // the CG's two-level preconditioner, when on
  // point_elastic_force: the set of a patch's nodes (one flag per node, cleared after each
  // use) and the elements touching them.
  std::vector<std::uint8_t> node_marks;
  std::vector<std::int32_t> element_scratch;
  // Sparse direct solver (kSparseLdlt): the pattern's ordering and symbolic analysis, made
  // once by make_state; each step copies values and factors numerically.
  std::unique_ptr<DirectSolver, DirectSolverDeleter> direct;
};

}  // namespace hof::mechanics::detail
