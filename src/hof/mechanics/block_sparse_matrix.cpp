#include "hof/mechanics/block_sparse_matrix.h"

#include <algorithm>

#include "hof/mechanics/parallel.h"

namespace hof::mechanics {

BlockSparseMatrix BlockSparseMatrix::from_pairs(
    std::int32_t block_rows, const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) {
  std::vector<std::pair<std::int32_t, std::int32_t>> entries;
  entries.reserve(pairs.size() * 2 + static_cast<std::size_t>(block_rows));
  for (std::int32_t i = 0; i < block_rows; ++i) entries.emplace_back(i, i);
  for (const auto& [a, b] : pairs) {
    entries.emplace_back(a, b);
    entries.emplace_back(b, a);
  }
  std::sort(entries.begin(), entries.end());
  entries.erase(std::unique(entries.begin(), entries.end()), entries.end());

  BlockSparseMatrix m;
  m.row_start_.assign(static_cast<std::size_t>(block_rows) + 1, 0);
  m.columns_.reserve(entries.size());
  m.diagonal_.assign(static_cast<std::size_t>(block_rows), -1);
  for (const auto& [row, col] : entries) {
    if (row == col) m.diagonal_[row] = static_cast<std::int64_t>(m.columns_.size());
    m.columns_.push_back(col);
    ++m.row_start_[row + 1];
  }
  for (std::size_t r = 0; r < static_cast<std::size_t>(block_rows); ++r) m.row_start_[r + 1] += m.row_start_[r];
  m.values_.assign(m.columns_.size() * 9, 0.0);
  return m;
}

std::int64_t BlockSparseMatrix::slot(std::int32_t row, std::int32_t col) const {
  const auto first = columns_.begin() + row_start_[row];
  const auto last = columns_.begin() + row_start_[row + 1];
  const auto it = std::lower_bound(first, last, col);
  return it != last && *it == col ? static_cast<std::int64_t>(it - columns_.begin()) : -1;
}

void BlockSparseMatrix::set_zero() {
  parallel_chunks(values_.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    std::fill(values_.begin() + static_cast<std::ptrdiff_t>(b), values_.begin() + static_cast<std::ptrdiff_t>(e), 0.0);
  });
}

void BlockSparseMatrix::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const double* xs = x.data();
  double* ys = y.data();
  const double* v = values_.data();
  parallel_chunks(static_cast<std::size_t>(block_rows()), 256, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      double y0 = 0.0, y1 = 0.0, y2 = 0.0;
      for (std::int64_t s = row_start_[r]; s < row_start_[r + 1]; ++s) {
        const double* a = v + 9 * s;
        const double* xc = xs + 3 * static_cast<std::int64_t>(columns_[s]);
        y0 += a[0] * xc[0] + a[1] * xc[1] + a[2] * xc[2];
        y1 += a[3] * xc[0] + a[4] * xc[1] + a[5] * xc[2];
        y2 += a[6] * xc[0] + a[7] * xc[1] + a[8] * xc[2];
      }
      ys[3 * r] = y0;
      ys[3 * r + 1] = y1;
      ys[3 * r + 2] = y2;
    }
  });
}

Eigen::MatrixXd BlockSparseMatrix::to_dense() const {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(block_rows());
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (std::int32_t r = 0; r < block_rows(); ++r) {
    for (std::int64_t s = row_start_[r]; s < row_start_[r + 1]; ++s) {
      d.block<3, 3>(3 * r, 3 * columns_[s]) = block(s);
    }
  }
  return d;
}

}  // namespace hof::mechanics
