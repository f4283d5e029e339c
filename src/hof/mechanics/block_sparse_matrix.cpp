#include "hof/mechanics/block_sparse_matrix.h"

#include <algorithm>
#include <cstring>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/simd_lanes.h"

namespace hof::mechanics {

BlockSparseMatrix BlockSparseMatrix::from_pairs(std::int32_t block_rows,
                                                const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) {
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
  m.mirror_.resize(m.columns_.size());
  for (std::int32_t r = 0; r < block_rows; ++r) {
    for (std::int64_t s = m.row_start_[r]; s < m.row_start_[r + 1]; ++s) m.mirror_[s] = m.slot(m.columns_[s], r);
  }
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

// y = A x over block rows [r0, r1), double precision, padded column-major blocks.
// Six independent accumulators (three columns × two blocks) keep the fused multiply-adds
// from waiting on each other: the loop is bound by loads, not by FMA latency.
static void multiply_block_rows(const std::int64_t* row_start, const std::int32_t* columns, const double* values,
                                const double* xs, double* ys, std::size_t r0, std::size_t r1) {
  constexpr std::int64_t kStride = BlockSparseMatrix::kBlockStride;
  for (std::size_t r = r0; r < r1; ++r) {
    std::int64_t s = row_start[r];
    const std::int64_t end = row_start[r + 1];
#if defined(__AVX2__) && defined(__FMA__)
    __m256d a0 = _mm256_setzero_pd(), a1 = _mm256_setzero_pd(), a2 = _mm256_setzero_pd();
    __m256d b0 = _mm256_setzero_pd(), b1 = _mm256_setzero_pd(), b2 = _mm256_setzero_pd();
    for (; s + 1 < end; s += 2) {
      const double* a = values + kStride * s;
      const double* xa = xs + 3 * static_cast<std::int64_t>(columns[s]);
      const double* xb = xs + 3 * static_cast<std::int64_t>(columns[s + 1]);
      a0 = _mm256_fmadd_pd(_mm256_loadu_pd(a), _mm256_broadcast_sd(xa), a0);
      a1 = _mm256_fmadd_pd(_mm256_loadu_pd(a + 4), _mm256_broadcast_sd(xa + 1), a1);
      a2 = _mm256_fmadd_pd(_mm256_loadu_pd(a + 8), _mm256_broadcast_sd(xa + 2), a2);
      b0 = _mm256_fmadd_pd(_mm256_loadu_pd(a + kStride), _mm256_broadcast_sd(xb), b0);
      b1 = _mm256_fmadd_pd(_mm256_loadu_pd(a + kStride + 4), _mm256_broadcast_sd(xb + 1), b1);
      b2 = _mm256_fmadd_pd(_mm256_loadu_pd(a + kStride + 8), _mm256_broadcast_sd(xb + 2), b2);
    }
    if (s < end) {
      const double* a = values + kStride * s;
      const double* xa = xs + 3 * static_cast<std::int64_t>(columns[s]);
      a0 = _mm256_fmadd_pd(_mm256_loadu_pd(a), _mm256_broadcast_sd(xa), a0);
      a1 = _mm256_fmadd_pd(_mm256_loadu_pd(a + 4), _mm256_broadcast_sd(xa + 1), a1);
      a2 = _mm256_fmadd_pd(_mm256_loadu_pd(a + 8), _mm256_broadcast_sd(xa + 2), a2);
    }
    const __m256d sum =
        _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(a0, b0), _mm256_add_pd(a1, b1)), _mm256_add_pd(a2, b2));
    alignas(32) double out[4];
    _mm256_store_pd(out, sum);
    ys[3 * r] = out[0];
    ys[3 * r + 1] = out[1];
    ys[3 * r + 2] = out[2];
#else
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
    for (; s < end; ++s) {
      const double* a = values + kStride * s;
      const double* xc = xs + 3 * static_cast<std::int64_t>(columns[s]);
      y0 += a[0] * xc[0] + a[4] * xc[1] + a[8] * xc[2];
      y1 += a[1] * xc[0] + a[5] * xc[1] + a[9] * xc[2];
      y2 += a[2] * xc[0] + a[6] * xc[1] + a[10] * xc[2];
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
                  [=](std::size_t r0, std::size_t r1) { multiply_block_rows(rows, cols, v, xs, ys, r0, r1); });
}

void BlockSparseMatrix::multiply_rows(const Eigen::VectorXd& x, Eigen::VectorXd& y, std::size_t first,
                                      std::size_t last) const {
  multiply_block_rows(row_start_.data(), columns_.data(), values_.data(), x.data(), y.data(), first, last);
}

void BlockSparseMatrix::prepare_single_precision() {
  const auto rows = static_cast<std::size_t>(block_rows());
  pair_start_.assign(rows + 1, 0);
  pair_columns_.clear();
  pair_slots_.clear();
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::int64_t s = row_start_[r]; s < row_start_[r + 1]; ++s) {
      pair_columns_.push_back(columns_[s]);
      pair_slots_.push_back(s);
    }
    if ((row_start_[r + 1] - row_start_[r]) % 2 != 0) {
      pair_columns_.push_back(static_cast<std::int32_t>(r));  // any valid column: the block is zero
      pair_slots_.push_back(-1);
    }
    pair_start_[r + 1] = static_cast<std::int64_t>(pair_columns_.size() / 2);
  }
  values_single_.assign(pair_columns_.size() * 12, 0.0f);
  single_offset_.assign(columns_.size(), 0);
  for (std::size_t k = 0; k < pair_slots_.size(); ++k) {
    if (pair_slots_[k] >= 0)
      single_offset_[static_cast<std::size_t>(pair_slots_[k])] = static_cast<std::int64_t>(24 * (k / 2) + 4 * (k % 2));
  }
}

void BlockSparseMatrix::multiply_single(const float* x4, Eigen::VectorXd& y) const {
  double* ys = y.data();
  parallel_chunks(static_cast<std::size_t>(block_rows()), 256,
                  [=, this](std::size_t r0, std::size_t r1) { multiply_single_rows(x4, ys, r0, r1); });
}

void BlockSparseMatrix::update_single_precision() {
  if (values_single_.size() != pair_columns_.size() * 12 || pair_columns_.empty()) prepare_single_precision();
  const std::size_t pairs = pair_columns_.size() / 2;
  parallel_chunks(pairs, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      float* to = values_single_.data() + 24 * k;
      for (int half = 0; half < 2; ++half) {
        const std::int64_t slot = pair_slots_[2 * k + static_cast<std::size_t>(half)];
        if (slot < 0) continue;  // padding stays zero
        for (int q = 0; q < 3; ++q) {
          // Lane 3 of each column is padding (zero in the double blocks too).
          simd::store_single(to + 8 * q + 4 * half, simd::load(values_.data() + kBlockStride * slot + 4 * q));
        }
      }
    }
  });
}

void BlockSparseMatrix::round_to_single(const double* x, float* x4, std::size_t first, std::size_t last) {
  std::size_t n = first;
#if defined(__AVX2__)
  // Four doubles from node n's x (its three and the next node's first), rounded, lane 3
  // cleared. The last node of the range is done alone: the double after it may belong to a
  // range another thread is writing.
  for (; n + 1 < last; ++n) {
    const __m128 rounded = _mm256_cvtpd_ps(_mm256_loadu_pd(x + 3 * n));
    _mm_storeu_ps(x4 + 4 * n, _mm_blend_ps(rounded, _mm_setzero_ps(), 0x8));
  }
#endif
  for (; n < last; ++n) {
    x4[4 * n] = static_cast<float>(x[3 * n]);
    x4[4 * n + 1] = static_cast<float>(x[3 * n + 1]);
    x4[4 * n + 2] = static_cast<float>(x[3 * n + 2]);
    x4[4 * n + 3] = 0.0f;
  }
}

void BlockSparseMatrix::multiply_single_rows(const float* x4, double* y, std::size_t first, std::size_t last) const {
  multiply_single_rows(x4, pair_columns_.data(), y, first, last);
}

void BlockSparseMatrix::multiply_single_rows(const float* x4, const std::int32_t* pair_columns, double* y,
                                             std::size_t first, std::size_t last) const {
  const std::int64_t* pair_start = pair_start_.data();
  const std::int32_t* cols = pair_columns;
  const float* values = values_single_.data();
  for (std::size_t r = first; r < last; ++r) {
#if defined(__AVX2__) && defined(__FMA__)
    // Lanes 0–3 accumulate the pair's first block, lanes 4–7 its second; column q of both
    // is multiplied by component q of their x, broadcast within each half.
    // Two pairs per iteration into separate sums: rows are short (six or seven pairs), so
    // single chains of multiply-adds would leave the loop waiting on their latency.
    __m256 acc0 = _mm256_setzero_ps(), acc1 = _mm256_setzero_ps(), acc2 = _mm256_setzero_ps();
    __m256 bcc0 = _mm256_setzero_ps(), bcc1 = _mm256_setzero_ps(), bcc2 = _mm256_setzero_ps();
    auto pair_x = [&](std::int64_t k) {
      return _mm256_set_m128(_mm_loadu_ps(x4 + 4 * static_cast<std::int64_t>(cols[2 * k + 1])),
                             _mm_loadu_ps(x4 + 4 * static_cast<std::int64_t>(cols[2 * k])));
    };
    std::int64_t k = pair_start[r];
    const std::int64_t end = pair_start[r + 1];
    for (; k + 1 < end; k += 2) {
      const float* v = values + 24 * k;
      const __m256 xa = pair_x(k);
      const __m256 xb = pair_x(k + 1);
      acc0 = _mm256_fmadd_ps(_mm256_load_ps(v), _mm256_permute_ps(xa, 0x00), acc0);
      acc1 = _mm256_fmadd_ps(_mm256_load_ps(v + 8), _mm256_permute_ps(xa, 0x55), acc1);
      acc2 = _mm256_fmadd_ps(_mm256_load_ps(v + 16), _mm256_permute_ps(xa, 0xAA), acc2);
      bcc0 = _mm256_fmadd_ps(_mm256_load_ps(v + 24), _mm256_permute_ps(xb, 0x00), bcc0);
      bcc1 = _mm256_fmadd_ps(_mm256_load_ps(v + 32), _mm256_permute_ps(xb, 0x55), bcc1);
      bcc2 = _mm256_fmadd_ps(_mm256_load_ps(v + 40), _mm256_permute_ps(xb, 0xAA), bcc2);
    }
    if (k < end) {
      const float* v = values + 24 * k;
      const __m256 xa = pair_x(k);
      acc0 = _mm256_fmadd_ps(_mm256_load_ps(v), _mm256_permute_ps(xa, 0x00), acc0);
      acc1 = _mm256_fmadd_ps(_mm256_load_ps(v + 8), _mm256_permute_ps(xa, 0x55), acc1);
      acc2 = _mm256_fmadd_ps(_mm256_load_ps(v + 16), _mm256_permute_ps(xa, 0xAA), acc2);
    }
    const __m256 sum8 =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(acc0, bcc0), _mm256_add_ps(acc1, bcc1)), _mm256_add_ps(acc2, bcc2));
    const __m128 sum4 = _mm_add_ps(_mm256_castps256_ps128(sum8), _mm256_extractf128_ps(sum8, 1));
    alignas(16) float out[4];
    _mm_store_ps(out, sum4);
    y[3 * r] = out[0];
    y[3 * r + 1] = out[1];
    y[3 * r + 2] = out[2];
#else
    float sum[3] = {0.0f, 0.0f, 0.0f};
    for (std::int64_t k = pair_start[r]; k < pair_start[r + 1]; ++k) {
      const float* v = values + 24 * k;
      for (int half = 0; half < 2; ++half) {
        const float* xc = x4 + 4 * static_cast<std::int64_t>(cols[2 * k + half]);
        for (int i = 0; i < 3; ++i) {
          sum[i] += v[4 * half + i] * xc[0] + v[8 + 4 * half + i] * xc[1] + v[16 + 4 * half + i] * xc[2];
        }
      }
    }
    y[3 * r] = sum[0];
    y[3 * r + 1] = sum[1];
    y[3 * r + 2] = sum[2];
#endif
  }
}

void BlockSparseMatrix::complete_from_upper(std::size_t first, std::size_t last) {
  for (std::size_t r = first; r < last; ++r) {
    const std::int64_t diagonal = diagonal_[r];
    simd::Lanes sum[3] = {simd::splat(0.0), simd::splat(0.0), simd::splat(0.0)};
    // Columns are sorted: the slots before the diagonal are below it.
    for (std::int64_t s = row_start_[r]; s < diagonal; ++s) {
      const double* upper = values_.data() + kBlockStride * mirror_[s];
      simd::Lanes transposed[4];
      simd::transpose_xyz(simd::load(upper), simd::load(upper + 4), simd::load(upper + 8), transposed);
      for (int q = 0; q < 3; ++q) {
        simd::store(values_.data() + kBlockStride * s + 4 * q, transposed[q]);
        sum[q] += transposed[q];
      }
    }
    for (std::int64_t s = diagonal + 1; s < row_start_[r + 1]; ++s) {
      for (int q = 0; q < 3; ++q) sum[q] += simd::load(values_.data() + kBlockStride * s + 4 * q);
    }
    for (int q = 0; q < 3; ++q) simd::store(values_.data() + kBlockStride * diagonal + 4 * q, -sum[q]);
  }
}

void BlockSparseMatrix::complete_from_upper_single(std::size_t first, std::size_t last) {
  using Floats4 = float __attribute__((vector_size(16)));
  constexpr std::int64_t kColumn = kSingleColumnStride;
  auto load4 = [](const float* p) {
    Floats4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
  };
  auto store4 = [](float* p, Floats4 v) { std::memcpy(p, &v, sizeof v); };
  for (std::size_t r = first; r < last; ++r) {
    const std::int64_t diagonal = diagonal_[r];
    Floats4 sum[3] = {};
    for (std::int64_t s = row_start_[r]; s < diagonal; ++s) {
      const float* upper = single_block(mirror_[s]);
      const Floats4 c0 = load4(upper), c1 = load4(upper + kColumn), c2 = load4(upper + 2 * kColumn);
      // Rows of the upper block (lane 3 of every column is zero) are the lower's columns.
      // (__builtin_shufflevector: GCC 12 and clang spell it alike; lanes of the second vector are 4–7.)
      const Floats4 lo01 = __builtin_shufflevector(c0, c1, 0, 4, 1, 5);  // c0₀ c1₀ c0₁ c1₁
      const Floats4 hi01 = __builtin_shufflevector(c0, c1, 2, 6, 3, 7);  // c0₂ c1₂ 0 0
      const Floats4 transposed[3] = {__builtin_shufflevector(lo01, c2, 0, 1, 4, 7),
                                     __builtin_shufflevector(lo01, c2, 2, 3, 5, 7),
                                     __builtin_shufflevector(hi01, c2, 0, 1, 6, 7)};
      float* lower = single_block(s);
      for (int q = 0; q < 3; ++q) {
        store4(lower + kColumn * q, transposed[q]);
        sum[q] += transposed[q];
      }
    }
    for (std::int64_t s = diagonal + 1; s < row_start_[r + 1]; ++s) {
      const float* block = single_block(s);
      for (int q = 0; q < 3; ++q) sum[q] += load4(block + kColumn * q);
    }
    float* block = single_block(diagonal);
    for (int q = 0; q < 3; ++q) store4(block + kColumn * q, -sum[q]);
  }
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
