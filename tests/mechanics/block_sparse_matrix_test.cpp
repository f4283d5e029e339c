#include "hof/mechanics/block_sparse_matrix.h"

#include <gtest/gtest.h>

namespace hof::mechanics {
namespace {

TEST(BlockSparseMatrix, PatternHasDiagonalAndBothDirections) {
  const auto m = BlockSparseMatrix::from_pairs(4, {{0, 1}, {1, 0}, {2, 3}});
  EXPECT_EQ(m.block_count(), 4 + 4);
  EXPECT_GE(m.slot(1, 0), 0);
  EXPECT_GE(m.slot(0, 1), 0);
  EXPECT_EQ(m.slot(0, 2), -1);
  EXPECT_EQ(m.diagonal_slot(2), m.slot(2, 2));
}

TEST(BlockSparseMatrix, MultiplyMatchesDense) {
  auto m = BlockSparseMatrix::from_pairs(3, {{0, 1}, {1, 2}});
  for (std::int64_t s = 0; s < m.block_count(); ++s) {
    for (int k = 0; k < 9; ++k) m.values()[9 * s + k] = static_cast<double>((s * 9 + k) % 7) - 3.0;
  }
  Eigen::VectorXd x(9), y(9);
  for (int i = 0; i < 9; ++i) x[i] = 0.5 * i - 1.0;
  m.multiply(x, y);
  EXPECT_LT((y - m.to_dense() * x).norm(), 1e-12);
}

}  // namespace
}  // namespace hof::mechanics
