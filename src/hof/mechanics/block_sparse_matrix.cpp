#include "hof/mechanics/block_sparse_matrix.h"

#include <algorithm>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

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
  m.values_.assign(m.columns_.size() * kBlockStride, 0.0);
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

namespace {

// Single-precision blocks are stored compact: 9 floats, column-major. A column is loaded as
// four floats starting at its first entry; the fourth lane then holds the next column's (or
// block's) first entry, which only ever reaches the discarded fourth lane of the sum.
constexpr std::int64_t kSingleStride = 9;

#if defined(__AVX2__) && defined(__FMA__)
inline __m256d load_column(const double* a) { return _mm256_loadu_pd(a); }
inline __m256d load_column(const float* a) { return _mm256_cvtps_pd(_mm_loadu_ps(a)); }

#endif

}  // namespace

// y = A x over block rows [r0, r1) for values of type T (double, or float widened on load).
// Six independent accumulators (three columns × two blocks) keep the fused multiply-adds
// from waiting on each other: the loop is bound by loads, not by FMA latency.
template <class T, std::int64_t kStride, std::int64_t kColumn>
static void multiply_block_rows(const std::int64_t* row_start, const std::int32_t* columns, const T* values, const double* xs,
                   double* ys, std::size_t r0, std::size_t r1) {
  for (std::size_t r = r0; r < r1; ++r) {
    std::int64_t s = row_start[r];
    const std::int64_t end = row_start[r + 1];
#if defined(__AVX2__) && defined(__FMA__)
    __m256d a0 = _mm256_setzero_pd(), a1 = _mm256_setzero_pd(), a2 = _mm256_setzero_pd();
    __m256d b0 = _mm256_setzero_pd(), b1 = _mm256_setzero_pd(), b2 = _mm256_setzero_pd();
    for (; s + 1 < end; s += 2) {
      const T* a = values + kStride * s;
      const double* xa = xs + 3 * static_cast<std::int64_t>(columns[s]);
      const double* xb = xs + 3 * static_cast<std::int64_t>(columns[s + 1]);
      a0 = _mm256_fmadd_pd(load_column(a), _mm256_broadcast_sd(xa), a0);
      a1 = _mm256_fmadd_pd(load_column(a + kColumn), _mm256_broadcast_sd(xa + 1), a1);
      a2 = _mm256_fmadd_pd(load_column(a + 2 * kColumn), _mm256_broadcast_sd(xa + 2), a2);
      b0 = _mm256_fmadd_pd(load_column(a + kStride), _mm256_broadcast_sd(xb), b0);
      b1 = _mm256_fmadd_pd(load_column(a + kStride + kColumn), _mm256_broadcast_sd(xb + 1), b1);
      b2 = _mm256_fmadd_pd(load_column(a + kStride + 2 * kColumn), _mm256_broadcast_sd(xb + 2), b2);
    }
    if (s < end) {
      const T* a = values + kStride * s;
      const double* xa = xs + 3 * static_cast<std::int64_t>(columns[s]);
      a0 = _mm256_fmadd_pd(load_column(a), _mm256_broadcast_sd(xa), a0);
      a1 = _mm256_fmadd_pd(load_column(a + kColumn), _mm256_broadcast_sd(xa + 1), a1);
      a2 = _mm256_fmadd_pd(load_column(a + 2 * kColumn), _mm256_broadcast_sd(xa + 2), a2);
    }
    const __m256d sum = _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(a0, b0), _mm256_add_pd(a1, b1)), _mm256_add_pd(a2, b2));
    alignas(32) double out[4];
    _mm256_store_pd(out, sum);
    ys[3 * r] = out[0];
    ys[3 * r + 1] = out[1];
    ys[3 * r + 2] = out[2];
#else
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
    for (; s < end; ++s) {
      const T* a = values + kStride * s;
      const double* xc = xs + 3 * static_cast<std::int64_t>(columns[s]);
      y0 += double(a[0]) * xc[0] + double(a[kColumn]) * xc[1] + double(a[2 * kColumn]) * xc[2];
      y1 += double(a[1]) * xc[0] + double(a[kColumn + 1]) * xc[1] + double(a[2 * kColumn + 1]) * xc[2];
      y2 += double(a[2]) * xc[0] + double(a[kColumn + 2]) * xc[1] + double(a[2 * kColumn + 2]) * xc[2];
    }
    ys[3 * r] = y0;
    ys[3 * r + 1] = y1;
    ys[3 * r + 2] = y2;
#endif
  }
}


void BlockSparseMatrix::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const std::int64_t* rows = row_start_.data();
  const std::int32_t* cols = columns_.data();
  const double* v = values_.data();
  const double* xs = x.data();
  double* ys = y.data();
  parallel_chunks(static_cast<std::size_t>(block_rows()), 256,
                  [=](std::size_t r0, std::size_t r1) { multiply_block_rows<double, kBlockStride, 4>(rows, cols, v, xs, ys, r0, r1); });
}

void BlockSparseMatrix::multiply_rows(const Eigen::VectorXd& x, Eigen::VectorXd& y, std::size_t first,
                                      std::size_t last) const {
  multiply_block_rows<double, kBlockStride, 4>(row_start_.data(), columns_.data(), values_.data(), x.data(), y.data(),
                                               first, last);
}

void BlockSparseMatrix::multiply_single_rows(const Eigen::VectorXd& x, Eigen::VectorXd& y, std::size_t first,
                                             std::size_t last) const {
  multiply_block_rows<float, kSingleStride, 3>(row_start_.data(), columns_.data(), values_single_.data(), x.data(),
                                               y.data(), first, last);
}

void BlockSparseMatrix::update_single_precision() {
  const auto blocks = static_cast<std::size_t>(block_count());
  values_single_.resize(blocks * kSingleStride + 4, 0.0f);  // tail: the last column's 4th lane
  parallel_chunks(blocks, 2048, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const double* from = values_.data() + kBlockStride * static_cast<std::int64_t>(k);
      float* to = values_single_.data() + kSingleStride * static_cast<std::int64_t>(k);
      for (int q = 0; q < 3; ++q) {
        for (int i = 0; i < 3; ++i) to[3 * q + i] = static_cast<float>(from[4 * q + i]);
      }
    }
  });
}

void BlockSparseMatrix::multiply_single(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const std::int64_t* rows = row_start_.data();
  const std::int32_t* cols = columns_.data();
  const float* v = values_single_.data();
  const double* xs = x.data();
  double* ys = y.data();
  parallel_chunks(static_cast<std::size_t>(block_rows()), 256,
                  [=](std::size_t r0, std::size_t r1) { multiply_block_rows<float, kSingleStride, 3>(rows, cols, v, xs, ys, r0, r1); });
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
