#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include <cholmod.h>
#include <dlfcn.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "hof/mechanics/detail/cg_kernels.h"
#include "hof/mechanics/detail/coarse_correction.h"
#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/vector_kernels.h"

namespace hof::mechanics::detail {

// The sparse direct solver: CHOLMOD (SuiteSparse; Chen, Davis, Hager, Rajamanickam, "Algorithm
// 887: CHOLMOD, supernodal sparse Cholesky factorization and update/downdate", ACM TOMS 35(3),
// 2008). Its supernodal LLᵀ factors dense blocks of columns with the BLAS, where a simplicial
// factorisation (Eigen's SimplicialLDLT, HoF's solver before issue 35) updates one column at a
// time through the sparse pattern.
//
// The fill-reducing ordering P (AMD or METIS, whichever leaves the sparser factor, followed by
// the elimination tree's postorder) is found once, when the state is made. The
// matrix handed to CHOLMOD is already P A Pᵀ (lower triangle, compressed columns, filled from
// block storage through a value map), and its symbolic analysis uses the natural order: so
// each step's numeric factorisation reads the values in place, with no permuted copy.
//
// Debian's CHOLMOD is built with OpenMP: a few copy loops of its supernodal factorisation ask
// for 4 threads (CHOLMOD_OMP_NUM_THREADS), whatever the model's thread setting. On 2 cores
// beside TBB's workers each of those regions' closing barriers waits for a descheduled thread
// (the coarse liver's step: 6.8 ms with them off, 36 ms on, docs/performance.md), the same
// stall that made HoF's CG drop a team of threads. So the factorisation runs with the calling
// thread's OpenMP max-active-levels at 0 (every region then runs on that thread alone), and
// the caller's value is restored after. The two OpenMP functions are looked up at run time:
// HoF links no OpenMP runtime itself, and with a CHOLMOD built without one there is nothing
// to do.
struct OpenMpLevels {
  using Get = int (*)();
  using Set = void (*)(int);
  Get get{reinterpret_cast<Get>(dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"))};
  Set set{reinterpret_cast<Set>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"))};
};

class SerialOpenMp {
 public:
  explicit SerialOpenMp(const OpenMpLevels& levels) : levels_(levels) {
    if (levels_.get != nullptr && levels_.set != nullptr) {
      saved_ = levels_.get();
      levels_.set(0);
    }
  }
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;
  ~SerialOpenMp() {
    if (levels_.get != nullptr && levels_.set != nullptr) levels_.set(saved_);
  }

 private:
  const OpenMpLevels& levels_;
  int saved_{0};
};

struct DirectSolver {
  DirectSolver() { cholmod_start(&common); }
  DirectSolver(const DirectSolver&) = delete;
  DirectSolver& operator=(const DirectSolver&) = delete;
  ~DirectSolver() {
    for (cholmod_dense** dense : {&solution, &workspace_y[0], &workspace_y[1], &workspace_e[0], &workspace_e[1]}) {
      if (*dense != nullptr) cholmod_free_dense(dense, &common);
    }
    for (cholmod_factor** factor : {&supernodal, &simplicial}) {
      if (*factor != nullptr) cholmod_free_factor(factor, &common);
    }
    cholmod_finish(&common);
  }

  cholmod_common common{};
  OpenMpLevels openmp;
  Eigen::SparseMatrix<double> lower;           // lower triangle of P A Pᵀ; values refilled each step
  std::vector<std::int64_t> lower_from_block;  // lower value k <- block value index
  std::vector<int> permutation;                // dof i of A is dof permutation[i] of P A Pᵀ
  cholmod_factor* supernodal{nullptr};         // supernodal LLᵀ of P A Pᵀ
  // Simplicial LDLᵀ of the same matrix, used when LLᵀ finds A not positive definite (a
  // static Newton step on a buckled hyperelastic body): LDLᵀ without pivoting, as before.
  cholmod_factor* simplicial{nullptr};
  cholmod_dense* solution{nullptr};                 // (n) P x
  cholmod_dense* workspace_y[2]{nullptr, nullptr};  // cholmod_solve2's workspace, per factor
  cholmod_dense* workspace_e[2]{nullptr, nullptr};
  detail::DirectOrdering ordering{detail::DirectOrdering::kNone};
  double factor_nonzeros{0.0};
  double factor_flops{0.0};
  std::int64_t factorisations{0};
  bool last_used_fallback{false};
};

void DirectSolverDeleter::operator()(DirectSolver* solver) const noexcept { delete solver; }

namespace {

// A CHOLMOD view of a compressed-column matrix (no copy): its lower triangle, symmetric.
cholmod_sparse view_lower(Eigen::SparseMatrix<double>& m) {
  cholmod_sparse a{};
  a.nrow = a.ncol = static_cast<std::size_t>(m.rows());
  a.nzmax = static_cast<std::size_t>(m.nonZeros());
  a.p = m.outerIndexPtr();
  a.i = m.innerIndexPtr();
  a.x = m.valuePtr();
  a.stype = -1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  return a;
}

DirectOrdering ordering_of(int cholmod_ordering) {
  switch (cholmod_ordering) {
    case CHOLMOD_AMD:
      return DirectOrdering::kAmd;
    case CHOLMOD_METIS:
      return DirectOrdering::kMetis;
    case CHOLMOD_NESDIS:
      return DirectOrdering::kNestedDissection;
    default:
      return DirectOrdering::kOther;
  }
}

// The conjugate-gradient solve's fixed split of the nodes: chunks of about 256 nodes, their
// count a multiple of 8. The static split gives each thread a contiguous run of chunks, and
// with 2, 4 or 8 threads the runs are then equal (37 chunks on two threads would leave one
// thread 7% more work, waited for at every pass). The chunks depend on the node count only,
// not on the threads: results do not either.
struct CgChunks {
  std::size_t count;
  std::size_t nodes_per_chunk;
  [[nodiscard]] std::size_t first_node(std::size_t chunk, std::size_t nodes) const {
    return std::min(nodes, chunk * nodes_per_chunk);
  }
  /// First chunk of part `part` of `parts` contiguous runs (one per thread).
  [[nodiscard]] std::size_t first_chunk(std::size_t part, std::size_t parts) const { return part * count / parts; }
};
CgChunks cg_chunks(std::size_t nodes) {
  const std::size_t count = (nodes + 256 * 8 - 1) / (256 * 8) * 8;
  return {count, (nodes + count - 1) / count};
}

// The CG's exchange between threads (see solve_cg). The chunks are split into one
// contiguous part per thread, as the solve's static split runs them; for each part, the
// nodes outside it that its rows read get a copy after the first N+1 nodes of the
// single-precision vector, the part's product columns point at the copies, and the chunk that
// owns a node writes its copies right after the node itself.
void prepare_cg_exchange(const MechanicalModel& model, SolverWorkspace& w, int threads) {
  w.cg_pair_columns.clear();
  w.cg_send_start.clear();
  w.cg_send_from.clear();
  w.cg_send_to.clear();
  const std::size_t nodes = model.node_count();
  const CgChunks split = cg_chunks(nodes);
  // Small systems are solved on one thread: the passes would cost more to share.
  w.cg_parts = 3 * nodes >= kParallelThreshold
                   ? std::min<std::size_t>(static_cast<std::size_t>(std::max(threads, 1)), split.count)
                   : 1;
  const std::size_t parts = w.cg_parts;
  if (!uses_single_precision(model) || parts < 2) return;
  const BlockSparseMatrix& a = w.system;
  const std::vector<std::int64_t>& pair_start = a.single_pair_start();
  w.cg_pair_columns = a.single_pair_columns();
  std::vector<std::pair<std::int32_t, std::int32_t>> sends;  // (node, copy)
  auto copy_index = static_cast<std::int32_t>(nodes + 1);
  std::vector<std::int32_t> copy_of(nodes, -1);
  for (std::size_t part = 0; part < parts; ++part) {
    const std::size_t first = split.first_node(split.first_chunk(part, parts), nodes);
    const std::size_t last = split.first_node(split.first_chunk(part + 1, parts), nodes);
    std::vector<std::int32_t> outside;
    for (std::size_t row = first; row < last; ++row) {
      for (std::int64_t k = 2 * pair_start[row]; k < 2 * pair_start[row + 1]; ++k) {
        const auto col = static_cast<std::size_t>(w.cg_pair_columns[static_cast<std::size_t>(k)]);
        if (col < first || col >= last) outside.push_back(static_cast<std::int32_t>(col));
      }
    }
    std::sort(outside.begin(), outside.end());
    outside.erase(std::unique(outside.begin(), outside.end()), outside.end());
    for (std::int32_t node : outside) {
      copy_of[static_cast<std::size_t>(node)] = copy_index;
      sends.emplace_back(node, copy_index++);
    }
    for (std::size_t row = first; row < last; ++row) {
      for (std::int64_t k = 2 * pair_start[row]; k < 2 * pair_start[row + 1]; ++k) {
        std::int32_t& col = w.cg_pair_columns[static_cast<std::size_t>(k)];
        if (static_cast<std::size_t>(col) < first || static_cast<std::size_t>(col) >= last)
          col = copy_of[static_cast<std::size_t>(col)];
      }
    }
  }
  // Sends by the chunk that owns the node, in node order.
  std::sort(sends.begin(), sends.end());
  w.cg_send_start.assign(split.count + 1, 0);
  std::size_t at = 0;
  for (std::size_t c = 0; c < split.count; ++c) {
    const std::size_t end = split.first_node(c + 1, nodes);
    while (at < sends.size() && static_cast<std::size_t>(sends[at].first) < end) {
      w.cg_send_from.push_back(sends[at].first);
      w.cg_send_to.push_back(sends[at].second);
      ++at;
    }
    w.cg_send_start[c + 1] = static_cast<std::int32_t>(w.cg_send_from.size());
  }
  w.p_single.assign(4 * static_cast<std::size_t>(copy_index) + 4, 0.0f);
}

}  // namespace

void prepare_cg_threads(const MechanicalModel& model, MechanicalState& state, int threads) {
  if (model.needs_matrix) prepare_cg_exchange(model, *state.work, threads);
}

void prepare_linear_solver(const MechanicalModel& model, MechanicalState& state, int threads) {
  SolverWorkspace& w = *state.work;
  if (model.needs_matrix) {
    w.system.prepare_single_precision();
    prepare_cg_exchange(model, w, threads);
    if (model.linear.kind == LinearSolverKind::kConjugateGradient && model.linear.coarse_correction) {
      prepare_coarse_space(model, w.coarse, cg_chunks(model.node_count()).count);
    }
  }
  if (model.linear.kind != LinearSolverKind::kSparseLdlt || !model.needs_matrix) return;
  // Compressed columns of the block matrix's lower triangle. Each triplet carries its
  // block-storage index + 1 as its value, which gives the map from compressed storage back to
  // block storage after compression.
  const BlockSparseMatrix& a = w.system;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(a.block_rows());
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(a.block_count()) * 9 / 2 + static_cast<std::size_t>(n));
  auto lower_of = [&](const std::vector<int>* permutation) {
    triplets.clear();
    for (std::int32_t r = 0; r < a.block_rows(); ++r) {
      for (std::int64_t s = a.row_start()[r]; s < a.row_start()[r + 1]; ++s) {
        const std::int32_t c = a.columns()[s];
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            int row = 3 * r + i;
            int col = 3 * c + j;
            if (permutation != nullptr) {
              row = (*permutation)[static_cast<std::size_t>(row)];
              col = (*permutation)[static_cast<std::size_t>(col)];
            }
            if (row >= col)
              triplets.emplace_back(row, col, static_cast<double>(BlockSparseMatrix::value_index(s, i, j) + 1));
          }
        }
      }
    }
    Eigen::SparseMatrix<double> m(n, n);
    m.setFromTriplets(triplets.begin(), triplets.end());
    m.makeCompressed();
    return m;
  };
  w.direct.reset(new DirectSolver);
  DirectSolver& d = *w.direct;
  cholmod_common& cc = d.common;
  cc.print = 0;  // failures are reported by the step, never printed
  // The ordering of A itself, with the elimination tree's postorder: AMD and METIS both tried,
  // the one with the sparser factor kept (CHOLMOD's default tries METIS only when AMD leaves
  // much fill; on the livers METIS's nested dissection halves the factorisation's flops:
  // docs/performance.md). The simplicial analysis suffices to choose.
  {
    Eigen::SparseMatrix<double> unpermuted = lower_of(nullptr);
    cholmod_sparse view = view_lower(unpermuted);
    cc.supernodal = CHOLMOD_SIMPLICIAL;
    cc.nmethods = 2;
    cc.method[0].ordering = CHOLMOD_AMD;
    cc.method[1].ordering = CHOLMOD_METIS;
    cholmod_factor* ordering = cholmod_analyze(&view, &cc);
    if (ordering == nullptr || cc.status != CHOLMOD_OK) {  // out of memory: every solve then fails
      if (ordering != nullptr) cholmod_free_factor(&ordering, &cc);
      w.direct.reset();
      return;
    }
    d.ordering = ordering_of(ordering->ordering);
    const int* p = static_cast<const int*>(ordering->Perm);  // row p[k] of A is row k of P A Pᵀ
    d.permutation.resize(static_cast<std::size_t>(n));
    for (Eigen::Index k = 0; k < n; ++k) d.permutation[static_cast<std::size_t>(p[k])] = static_cast<int>(k);
    cholmod_free_factor(&ordering, &cc);
  }
  d.lower = lower_of(&d.permutation);
  d.lower_from_block.resize(static_cast<std::size_t>(d.lower.nonZeros()));
  for (Eigen::Index k = 0; k < d.lower.nonZeros(); ++k) {
    d.lower_from_block[static_cast<std::size_t>(k)] = static_cast<std::int64_t>(d.lower.valuePtr()[k]) - 1;
  }
  // Symbolic analyses of P A Pᵀ in its own (natural, already postordered) order, kept while
  // the pattern holds: the supernodal LLᵀ and the simplicial LDLᵀ fallback.
  cc.nmethods = 1;
  cc.method[0].ordering = CHOLMOD_NATURAL;
  cc.postorder = 0;
  cholmod_sparse view = view_lower(d.lower);
  cc.supernodal = CHOLMOD_SUPERNODAL;
  d.supernodal = cholmod_analyze(&view, &cc);
  d.factor_nonzeros = cc.lnz;
  d.factor_flops = cc.fl;
  cc.supernodal = CHOLMOD_SIMPLICIAL;
  d.simplicial = cholmod_analyze(&view, &cc);
  d.solution = cholmod_allocate_dense(static_cast<std::size_t>(n), 1, static_cast<std::size_t>(n), CHOLMOD_REAL, &cc);
  if (d.supernodal == nullptr || d.simplicial == nullptr || d.solution == nullptr) w.direct.reset();  // out of memory
}

DirectSolverInfo direct_solver_info(const MechanicalState& state) {
  const DirectSolver* d = state.work->direct.get();
  if (d == nullptr) return {};
  return {true,
          d->supernodal != nullptr && d->supernodal->is_super != 0,
          d->last_used_fallback,
          d->factorisations,
          d->ordering,
          d->factor_nonzeros,
          d->factor_flops};
}

namespace {

// Numeric factorisation of this step's A (supernodal LLᵀ; simplicial LDLᵀ if A is not
// positive definite), then the solve, both on P A Pᵀ.
bool solve_direct(MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  SolverWorkspace& w = *state.work;
  if (!w.direct) return false;  // its analysis ran out of memory
  DirectSolver& d = *w.direct;
  cholmod_common& cc = d.common;
  const double* block_values = w.system.values();
  double* lower_values = d.lower.valuePtr();
  for (std::size_t k = 0; k < d.lower_from_block.size(); ++k) lower_values[k] = block_values[d.lower_from_block[k]];
  cholmod_sparse a = view_lower(d.lower);
  const std::size_t n = d.permutation.size();
  // A factor is good when it completed (minor = n: no pivot stopped it) without an error.
  auto factor = [&](cholmod_factor* l) {
    const SerialOpenMp serial(d.openmp);
    ++d.factorisations;
    return cholmod_factorize(&a, l, &cc) != 0 && cc.status == CHOLMOD_OK && l->minor == n;
  };
  d.last_used_fallback = !factor(d.supernodal);
  if (d.last_used_fallback && !factor(d.simplicial)) return false;
  cholmod_factor* l = d.last_used_fallback ? d.simplicial : d.supernodal;
  const int which = d.last_used_fallback ? 1 : 0;
  // Solve P A Pᵀ (P x) = P b: P b in w.z, viewed as CHOLMOD's right-hand side; the solution
  // and solve2's workspace are kept from one solve to the next.
  for (std::size_t i = 0; i < n; ++i) w.z[d.permutation[i]] = b[static_cast<Eigen::Index>(i)];
  cholmod_dense rhs{};
  rhs.nrow = rhs.nzmax = rhs.d = n;
  rhs.ncol = 1;
  rhs.x = w.z.data();
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  if (cholmod_solve2(CHOLMOD_A, l, &rhs, nullptr, &d.solution, nullptr, &d.workspace_y[which], &d.workspace_e[which],
                     &cc) == 0) {
    return false;
  }
  const double* px = static_cast<const double*>(d.solution->x);
  for (std::size_t i = 0; i < n; ++i) x[static_cast<Eigen::Index>(i)] = px[d.permutation[i]];
  state.stats.linear_iterations = 1;
  state.stats.linear_residual = 0.0;
  return x.allFinite();
}

// The two-level preconditioner's coarse matrix, formed again every few steps.
void refresh_coarse_space(const MechanicalModel& model, MechanicalState& state) {
  const LinearSolverConfig& cfg = model.linear;
  const CoarseSpace& coarse = state.work->coarse;
  if (cfg.coarse_correction && coarse.aggregates > 0 &&
      (coarse.built_step < 0 || state.steps < coarse.built_step ||
       state.steps - coarse.built_step >= cfg.coarse_refresh_steps)) {
    build_coarse_space(model, state);
  }
}

// Ax₀ for a warm start from x₀ = `guess`, into `product` (with mixed precision through the
// single-precision copy of x₀ in `guess_single`).
void warm_start_product(const BlockSparseMatrix& a, bool single, const Eigen::VectorXd& guess, float* guess_single,
                        Eigen::VectorXd& product) {
  if (single) {
    const auto nodes = static_cast<std::size_t>(a.block_rows());
    parallel_chunks(nodes, 1024, [&](std::size_t n0, std::size_t n1) {
      BlockSparseMatrix::round_to_single(guess.data(), guess_single, n0, n1);
    });
    a.multiply_single(guess_single, product);
  } else {
    a.multiply(guess, product);
  }
}

// The inverse diagonal of A's rows [n0, n1) (the two-level preconditioner's fine part).
void invert_diagonal(const BlockSparseMatrix& a, bool single, std::size_t n0, std::size_t n1,
                     double* diagonal_inverse) {
  for (std::size_t n = n0; n < n1; ++n) {
    const std::int64_t slot = a.diagonal_slot(static_cast<std::int32_t>(n));
    for (int q = 0; q < 3; ++q) {
      const double entry =
          single ? static_cast<double>(a.single_block(slot)[BlockSparseMatrix::kSingleColumnStride * q + q])
                 : a.block(slot)(q, q);
      diagonal_inverse[3 * n + static_cast<std::size_t>(q)] = 1.0 / entry;
    }
  }
}

// The inverse 3x3 diagonal blocks of A's rows [n0, n1) (block Jacobi).
void invert_diagonal_blocks(const BlockSparseMatrix& a, bool single, std::size_t n0, std::size_t n1, Mat3* jacobi) {
  for (std::size_t n = n0; n < n1; ++n) {
    const std::int64_t slot = a.diagonal_slot(static_cast<std::int32_t>(n));
    if (single) {
      const float* block = a.single_block(slot);
      Mat3 diagonal;
      for (int q = 0; q < 3; ++q) {
        for (int i = 0; i < 3; ++i) diagonal(i, q) = block[BlockSparseMatrix::kSingleColumnStride * q + i];
      }
      jacobi[n] = diagonal.inverse();
    } else {
      jacobi[n] = a.block(slot).inverse();
    }
  }
}

// Conjugate gradients with SOFA's CGLinearSolver stopping rules: stop when |r|²/|b|² falls
// below `tolerance`, or when the curvature pᵀAp falls below `threshold` (relative, see
// below), or after `iterations`. Optional block-Jacobi preconditioning (inverse 3x3 diagonal
// blocks).
//
// Two passes over fixed node chunks per iteration, with per-chunk partial sums added in
// chunk order (the result does not depend on the number of threads):
//   A: x += αp, r −= αAp, z = M⁻¹r, with rᵀr and rᵀz;
//   B: Az, then p = z + βp and Ap = Az + βAp (the product of the new direction by
//      linearity, so p need not be complete before the product starts), with pᵀAp.
// The textbook order needs a third pass (the p update) and a third wait. With mixed
// precision the product reads z rounded to single precision, written by pass A.
//
// The passes are task loops (TBB), not one team of threads with barriers between them: a
// team is faster by a few microseconds per pass on an idle machine but stalls at every
// barrier when the machine is oversubscribed and one of its threads is descheduled, while a
// task loop lets the running threads take over the waiting chunks.
//
// Why this function stays long (~190 lines): its stages (the first residual, the two-level
// correction, the direction pass, the solution pass) are lambdas over one set of a dozen raw
// pointers and three partial-sum arrays, and each runs as the body of a task loop. As
// lambdas they are inlined into those bodies, and the fused passes share their loads; as
// separate functions each would take the whole set as arguments. What does not share them
// (the coarse refresh, the warm start's product, the diagonal inversions) is outside.
bool solve_cg(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  SolverWorkspace& w = *state.work;
  const LinearSolverConfig& cfg = model.linear;
  const BlockSparseMatrix& a = w.system;
  const std::size_t nodes = model.node_count();
  refresh_coarse_space(model, state);
  CoarseSpace& coarse = w.coarse;
  const bool two_level = cfg.coarse_correction && coarse.usable;
  const bool precondition = cfg.block_jacobi || two_level;
  // The two-level preconditioner's fine part is plain Jacobi, taken once per assembled matrix
  // (a 3x3 block inverse per node costs more than the whole coarse solve).
  double* diagonal_inverse = w.diag_inv.data();
  const bool fresh_diagonal = two_level && w.diag_inv_assembly != w.system_assemblies;
  w.diag_inv_assembly = w.system_assemblies;
  const bool single = cfg.mixed_precision;
  const CgChunks split = cg_chunks(nodes);
  const std::size_t chunks = split.count;
  if (w.partials.size() < 3 * chunks) w.partials.resize(3 * chunks);  // sized by make_state
  double* part0 = w.partials.data();
  double* part1 = part0 + chunks;
  double* part2 = part1 + chunks;
  auto sum = [&](const double* parts) {
    double total = 0.0;
    for (std::size_t c = 0; c < chunks; ++c) total += parts[c];
    return total;
  };
  // Runs body(chunk, first dof, end dof) over all chunks: one task per part (a thread's
  // contiguous run of chunks, the parts of the exchange below), each part's chunks in order.
  const std::size_t parts = std::max<std::size_t>(w.cg_parts, 1);
  auto over_chunks = [&](auto&& body) {
    parallel_chunks(
        parts, 1,
        [&](std::size_t p0, std::size_t p1) {
          for (std::size_t c = split.first_chunk(p0, parts); c < split.first_chunk(p1, parts); ++c) {
            body(c, 3 * split.first_node(c, nodes), 3 * split.first_node(c + 1, nodes));
          }
        },
        /*min_parallel=*/1);
  };

  double* xs = x.data();
  double* rs = w.r.data();
  const Eigen::VectorXd& z = precondition ? w.z : w.r;
  double* zs = precondition ? w.z.data() : w.r.data();
  double* ps = w.p.data();
  double* aps = w.ap.data();
  double* azs = w.az.data();
  const double* bs = b.data();
  Mat3* jacobi = w.block_jacobi.data();
  float* z_single = w.p_single.data();
  auto apply_preconditioner = [&](std::size_t d0, std::size_t d1) {
    for (std::size_t n = d0 / 3; n < d1 / 3; ++n) {
      Eigen::Map<Eigen::Vector3d>(zs + 3 * n) = jacobi[n] * Eigen::Map<const Eigen::Vector3d>(rs + 3 * n);
    }
  };
  // The two-level preconditioner needs all of Pᵀr before any of z: each chunk adds its nodes'
  // share into its own partial (restrict), the partials are added in chunk order and the
  // coarse system solved on this thread (solve_coarse), then a second pass makes
  // z = D⁻¹r + P y (finish_two_level).
  const std::size_t coarse_size = two_level ? static_cast<std::size_t>(coarse.solution.size()) : 0;
  auto restrict_chunk = [&](std::size_t c, std::size_t d0, std::size_t d1) {
    double* partial = coarse.partials.data() + c * coarse_size;
    std::fill(partial, partial + coarse_size, 0.0);
    restrict_to_coarse(model, coarse, rs, d0 / 3, d1 / 3, partial);
  };
  auto solve_coarse = [&] {
    double* y = coarse.solution.data();
    std::fill(y, y + coarse_size, 0.0);
    for (std::size_t c = 0; c < chunks; ++c) {
      const double* partial = coarse.partials.data() + c * coarse_size;
      for (std::size_t k = 0; k < coarse_size; ++k) y[k] += partial[k];
    }
    coarse.factor.solveInPlace(coarse.solution);
  };
  // Between threads, each pass B reads the boundary entries of z that other threads wrote in
  // pass A. Read where they lie, those entries are scattered over a few hundred cache lines,
  // each fetched from the other core one at a time; their copies in a compact block (made by
  // the owning chunk in pass A, see prepare_cg_exchange) take a handful of lines. On the
  // 2-vCPU machine that cut the solve's time by a fifth at `medium` and `fine`
  // (docs/performance.md). The values, and so the results, are the same.
  const bool exchange = single && !w.cg_pair_columns.empty();
  const std::int32_t* product_columns = exchange ? w.cg_pair_columns.data() : a.single_pair_columns().data();
  auto publish = [&](std::size_t c) {
    if (!exchange) return;
    for (std::int32_t k = w.cg_send_start[c]; k < w.cg_send_start[c + 1]; ++k) {
      const auto k_index = static_cast<std::size_t>(k);
      std::memcpy(z_single + 4 * static_cast<std::size_t>(w.cg_send_to[k_index]),
                  z_single + 4 * static_cast<std::size_t>(w.cg_send_from[k_index]), 4 * sizeof(float));
    }
  };
  // Az over the rows of [d0, d1).
  auto multiply_z = [&](std::size_t d0, std::size_t d1) {
    if (single)
      a.multiply_single_rows(z_single, product_columns, azs, d0 / 3, d1 / 3);
    else
      a.multiply_rows(z, w.az, d0 / 3, d1 / 3);
  };

  // A warm start begins at the last solution x₀: its residual b − A x₀ needs one product
  // (into Ap, which the first direction pass overwrites), made as the iterations make theirs.
  const bool warm = cfg.warm_start && w.cg_previous.size() == x.size();
  const double* guess = w.cg_previous.data();
  if (warm) warm_start_product(a, single, w.cg_previous, z_single, w.ap);

  // r = b − A x₀, z = M⁻¹ r, x = x₀ (0 unless warm); |b|², rᵀz and |r|².
  over_chunks([&](std::size_t c, std::size_t d0, std::size_t d1) {
    for (std::size_t d = d0; d < d1; ++d) {
      xs[d] = warm ? guess[d] : 0.0;
      rs[d] = warm ? bs[d] - aps[d] : bs[d];
    }
    const double bb = dot_range(bs, bs, d0, d1);
    if (two_level) {
      if (fresh_diagonal) invert_diagonal(a, single, d0 / 3, d1 / 3, diagonal_inverse);
      restrict_chunk(c, d0, d1);
    } else if (precondition) {
      invert_diagonal_blocks(a, single, d0 / 3, d1 / 3, jacobi);
      apply_preconditioner(d0, d1);
    }
    part0[c] = bb;
    part2[c] = warm ? dot_range(rs, rs, d0, d1) : bb;
    if (two_level) return;  // z after the coarse solve
    if (single) BlockSparseMatrix::round_to_single(zs, z_single, d0 / 3, d1 / 3);
    publish(c);
    part1[c] = dot_range(rs, zs, d0, d1);
  });
  // z = D⁻¹r + P y and rᵀz, for the two-level preconditioner.
  auto finish_two_level = [&](double* rz_parts) {
    solve_coarse();
    over_chunks([&](std::size_t c, std::size_t d0, std::size_t d1) {
      for (std::size_t d = d0; d < d1; ++d) zs[d] = diagonal_inverse[d] * rs[d];
      prolong_from_coarse(model, coarse, coarse.solution.data(), d0 / 3, d1 / 3, zs);
      if (single) BlockSparseMatrix::round_to_single(zs, z_single, d0 / 3, d1 / 3);
      publish(c);
      rz_parts[c] = dot_range(rs, zs, d0, d1);
    });
  };
  if (two_level) finish_two_level(part1);
  const double b_norm2 = sum(part0);
  double rho = sum(part1);
  state.stats.linear_iterations = 0;
  state.stats.linear_residual = 0.0;
  if (!(b_norm2 > 0.0)) {
    if (warm) x.setZero();  // b = 0: the solution is 0, whatever the guess
    return std::isfinite(b_norm2);
  }

  // Pass B with β = 0: p = z, Ap = Az; pᵀAp.
  auto direction_pass = [&](double beta) {
    over_chunks([&](std::size_t c, std::size_t d0, std::size_t d1) {
      multiply_z(d0, d1);
      part0[c] = cg_update_direction(ps, aps, zs, azs, beta, d0 / 3, d1 / 3);
    });
  };
  double r_norm2 = sum(part2);
  double first_curvature = 0.0;
  int iteration = 0;
  if (cfg.iterations > 0 && r_norm2 / b_norm2 > cfg.tolerance) direction_pass(0.0);
  for (; iteration < cfg.iterations; ++iteration) {
    if (r_norm2 / b_norm2 <= cfg.tolerance) break;
    const double curvature = sum(part0);
    // SOFA compares pᵀAp with `threshold` in absolute terms, which in its unit-free scenes
    // means "the denominator vanished". In SI units (kg, m) pᵀAp is legitimately tiny, so
    // the same intent is kept scale-free: relative to the first iteration's curvature.
    if (iteration == 0) first_curvature = std::abs(curvature);
    if (!(std::abs(curvature) > cfg.threshold * first_curvature) || !(first_curvature > 0.0)) break;
    const double alpha = rho / curvature;
    // The last iteration's z would serve only a next direction: it is not made (with the
    // two-level preconditioner that is a coarse solve and two passes over the nodes).
    const bool last = iteration + 1 >= cfg.iterations;
    // Pass A: x += αp, r −= αAp, z = M⁻¹r; rᵀr and rᵀz.
    over_chunks([&](std::size_t c, std::size_t d0, std::size_t d1) {
      // Without a preconditioner z is r: the update rounds it for the product as it goes.
      const double rr = cg_update_solution(xs, rs, ps, aps, alpha,
                                           single && !precondition && !last ? z_single : nullptr, d0 / 3, d1 / 3);
      double rz = rr;
      if (last) {
        part1[c] = rr;
        part2[c] = rz;
        return;
      }
      if (two_level) {
        restrict_chunk(c, d0, d1);
        part1[c] = rr;
        return;  // z after the coarse solve
      }
      if (precondition) {
        apply_preconditioner(d0, d1);
        rz = dot_range(rs, zs, d0, d1);
        if (single) BlockSparseMatrix::round_to_single(zs, z_single, d0 / 3, d1 / 3);
      }
      publish(c);
      part1[c] = rr;
      part2[c] = rz;
    });
    if (two_level && !last) finish_two_level(part2);
    r_norm2 = sum(part1);
    const double rho_next = sum(part2);
    // The next direction is needed only if another iteration follows.
    if (iteration + 1 < cfg.iterations && r_norm2 / b_norm2 > cfg.tolerance) direction_pass(rho_next / rho);
    rho = rho_next;
  }
  state.stats.linear_iterations = iteration;
  state.stats.linear_residual = r_norm2 / b_norm2;
  const bool finite = std::isfinite(r_norm2) && x.allFinite();
  if (cfg.warm_start && finite) w.cg_previous = x;  // sized by make_state: no allocation
  return finite;
}

}  // namespace

bool solve_system(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  if (model.linear.kind == LinearSolverKind::kSparseLdlt) return solve_direct(state, b, x);
  return solve_cg(model, state, b, x);
}

}  // namespace hof::mechanics::detail
