#pragma once
/// @file
/// A symmetric-pattern sparse matrix of 3x3 blocks (one block row per node), the system matrix
/// of the implicit solvers. The pattern is fixed when the model is built (from the node pairs
/// the force fields couple); each step only refills the values, and force fields write into
/// precomputed block slots, so assembly does no search and no allocation.

#include <Eigen/Core>
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

  /// The 3x3 block stored at `slot` (row-major).
  [[nodiscard]] Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> block(std::int64_t slot) {
    return Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values_.data() + 9 * slot);
  }
  [[nodiscard]] Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> block(std::int64_t slot) const {
    return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values_.data() + 9 * slot);
  }
  [[nodiscard]] double* values() { return values_.data(); }
  [[nodiscard]] const double* values() const { return values_.data(); }
  [[nodiscard]] const std::vector<std::int64_t>& row_start() const { return row_start_; }
  [[nodiscard]] const std::vector<std::int32_t>& columns() const { return columns_; }

  void set_zero();

  /// y = A x (parallel over block rows; each row is summed in column order: deterministic).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;

  /// Dense copy, for tests and small problems.
  [[nodiscard]] Eigen::MatrixXd to_dense() const;

 private:
  std::vector<std::int64_t> row_start_{0};  // (rows+1) first slot of each block row
  std::vector<std::int32_t> columns_;       // (blocks) column of each slot, sorted per row
  std::vector<std::int64_t> diagonal_;      // (rows) slot of the diagonal block
  std::vector<double> values_;              // (9*blocks) row-major 3x3 blocks
};

}  // namespace hof::mechanics
