#pragma once
/// @file
/// A symmetric-pattern sparse matrix of 3x3 blocks (one block row per node), the system matrix
/// of the implicit solvers. The pattern is fixed when the model is built (from the node pairs
/// the force fields couple); each step only refills the values, and force fields write into
/// precomputed block slots, so assembly does no search and no allocation.
///
/// Storage: each block is column-major with its columns padded to four doubles (12 values,
/// the fourth of each column always zero). The product then needs three 4-wide fused
/// multiply-adds per block (y += a₀x₀ + a₁x₁ + a₂x₂ with broadcast x), which is what makes
/// the conjugate-gradient solve fast.

#include <Eigen/Core>
#include <Eigen/StdVector>
#include <cstdint>
#include <utility>
#include <vector>

#include "hof/core/types.h"

namespace hof::mechanics {

class BlockSparseMatrix {
 public:
  BlockSparseMatrix() = default;

  /// Builds the pattern for `block_rows` nodes: the diagonal plus both (i,j) and (j,i) for
  /// every listed pair. Duplicates are merged.
  static BlockSparseMatrix from_pairs(std::int32_t block_rows,
                                      const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs);

  [[nodiscard]] std::int32_t block_rows() const { return static_cast<std::int32_t>(row_start_.size()) - 1; }
  [[nodiscard]] std::int64_t block_count() const { return static_cast<std::int64_t>(columns_.size()); }

  /// Slot of block (row, col), or -1 when it is not in the pattern. O(log row length); for
  /// precomputation, not for inner loops.
  [[nodiscard]] std::int64_t slot(std::int32_t row, std::int32_t col) const;
  /// Slot of the diagonal block of `row`.
  [[nodiscard]] std::int64_t diagonal_slot(std::int32_t row) const { return diagonal_[row]; }

  /// Doubles per stored block.
  static constexpr std::int64_t kBlockStride = 12;
  using BlockRef = Eigen::Map<Eigen::Matrix3d, 0, Eigen::OuterStride<4>>;
  using ConstBlockRef = Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<4>>;

  /// The 3x3 block stored at `slot`.
  [[nodiscard]] BlockRef block(std::int64_t slot) { return BlockRef(values_.data() + kBlockStride * slot); }
  [[nodiscard]] ConstBlockRef block(std::int64_t slot) const {
    return ConstBlockRef(values_.data() + kBlockStride * slot);
  }
  /// Index in values() of entry (i, j) of the block at `slot`.
  [[nodiscard]] static std::int64_t value_index(std::int64_t slot, int i, int j) {
    return kBlockStride * slot + 4 * j + i;
  }
  [[nodiscard]] double* values() { return values_.data(); }
  [[nodiscard]] const double* values() const { return values_.data(); }
  [[nodiscard]] const std::vector<std::int64_t>& row_start() const { return row_start_; }
  [[nodiscard]] const std::vector<std::int32_t>& columns() const { return columns_; }

  void set_zero();

  /// y = A x (parallel over block rows; each row is summed in column order: deterministic).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;

  /// Single-precision copy for the conjugate-gradient product. The copy stores each block
  /// row's blocks in pairs, a pair's columns interleaved so that one 8-float register holds
  /// the same column of both blocks: the product then does two blocks per fused multiply-add
  /// with no conversions, half the instructions of a double-precision product, and the copy
  /// (36–48 bytes a block) stays in the core's cache for livers up to ~10k tetrahedra.
  /// prepare_single_precision() lays the copy out (once, it allocates);
  /// update_single_precision() refreshes its values (each step, it does not).
  void prepare_single_precision();
  void update_single_precision();
  /// Rounds x (3 per node) into the padded single-precision layout the product reads
  /// (4 per node, the fourth zero), for nodes [first, last).
  static void round_to_single(const double* x, float* x4, std::size_t first, std::size_t last);
  /// Rows [first, last) of y = A x with the single-precision copy; x4 from round_to_single.
  void multiply_single_rows(const float* x4, double* y, std::size_t first, std::size_t last) const;
  /// The same with the block columns of the copy replaced by `pair_columns` (same shape as
  /// single_pair_columns()): for a caller that places some entries of x elsewhere in x4.
  void multiply_single_rows(const float* x4, const std::int32_t* pair_columns, double* y, std::size_t first,
                            std::size_t last) const;
  /// The single-precision copy's column of each block in its pairs (two per pair; a padding
  /// block repeats its row).
  [[nodiscard]] const std::vector<std::int32_t>& single_pair_columns() const { return pair_columns_; }
  /// First pair of each block row of the single-precision copy (rows+1).
  [[nodiscard]] const std::vector<std::int64_t>& single_pair_start() const { return pair_start_; }
  /// y = A x with the single-precision copy (parallel over block rows).
  void multiply_single(const float* x4, Eigen::VectorXd& y) const;
  /// The single-precision block at `slot`: entry (i, q) at [8q + i]. For assembling straight
  /// into the copy (the double values are then not kept).
  [[nodiscard]] float* single_block(std::int64_t slot) { return values_single_.data() + single_offset_[slot]; }
  [[nodiscard]] const float* single_block(std::int64_t slot) const {
    return values_single_.data() + single_offset_[slot];
  }
  /// Row stride of a single-precision block's columns.
  static constexpr std::int64_t kSingleColumnStride = 8;

  /// Rows [first, last) of y = A x.
  void multiply_rows(const Eigen::VectorXd& x, Eigen::VectorXd& y, std::size_t first, std::size_t last) const;

  /// Slot of the transposed block: (col, row) for the block (row, col) at `slot`.
  [[nodiscard]] std::int64_t mirror_slot(std::int64_t slot) const { return mirror_[slot]; }

  /// Completes a symmetric stiffness written above the diagonal only, for rows [first, last),
  /// in the double values or in the single-precision copy: each block below the diagonal is
  /// set to the transpose of its mirror, and the diagonal block to minus the sum of the
  /// row's other blocks. That diagonal holds for any stiffness that rigid translations do
  /// not load (Σ_j K_ij = 0 for each i, as for every element of linear or co-rotational
  /// elasticity and every spring). Why: the force fields then write each node pair once, in
  /// row order, and this pass reads the mirrors; scattered writes to the lower half (each a
  /// cache line fetched and written back) cost more than the whole rest of the assembly.
  void complete_from_upper(std::size_t first, std::size_t last);
  void complete_from_upper_single(std::size_t first, std::size_t last);

  /// Dense copy, for tests and small problems.
  [[nodiscard]] Eigen::MatrixXd to_dense() const;

 private:
  std::vector<std::int64_t> row_start_{0};  // (rows+1) first slot of each block row
  std::vector<std::int32_t> columns_;       // (blocks) column of each slot, sorted per row
  std::vector<std::int64_t> diagonal_;      // (rows) slot of the diagonal block
  std::vector<std::int64_t> mirror_;        // (blocks) slot of the transposed block
  std::vector<double> values_;              // (12*blocks) column-major padded 3x3 blocks
  // Single-precision copy: per block row, its blocks in pairs (an odd row ends with a zero
  // block), 24 floats a pair: column q of both blocks in floats [8q, 8q+8).
  std::vector<std::int64_t> pair_start_;     // (rows+1) first pair of each block row
  std::vector<std::int32_t> pair_columns_;   // (2*pairs) block column of each pair member
  std::vector<std::int64_t> pair_slots_;     // (2*pairs) source slot, -1 for padding
  std::vector<std::int64_t> single_offset_;  // (blocks) first float of each slot's block
  std::vector<float, Eigen::aligned_allocator<float>> values_single_;
};

}  // namespace hof::mechanics
