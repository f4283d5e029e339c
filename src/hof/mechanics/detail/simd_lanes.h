#pragma once
/// @file
/// Four doubles processed as one value (GCC vector extension): element loops run four
/// elements at a time with the same code the scalar version would have. With AVX the type is
/// one register; without it GCC splits each operation in two SSE2 halves.

#if defined(__AVX__)
#include <immintrin.h>
#endif
#include <cmath>
#include <cstring>

// Returning 32-byte vectors changes the ABI between AVX and non-AVX code; these helpers are
// inline and never cross a library boundary.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace hof::mechanics::simd {

using Lanes = double __attribute__((vector_size(32)));
inline constexpr int kLanes = 4;

[[nodiscard]] inline Lanes splat(double v) { return Lanes{v, v, v, v}; }

[[nodiscard]] inline Lanes sqrt(Lanes v) {
#if defined(__AVX__)
  return _mm256_sqrt_pd(v);
#else
  return Lanes{std::sqrt(v[0]), std::sqrt(v[1]), std::sqrt(v[2]), std::sqrt(v[3])};
#endif
}

/// Four consecutive doubles from any (8-byte aligned) address.
[[nodiscard]] inline Lanes load(const double* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(double* p, Lanes v) { std::memcpy(p, &v, sizeof v); }

/// The four lanes rounded to single precision, stored at p.
inline void store_single(float* p, Lanes v) {
#if defined(__AVX__)
  _mm_storeu_ps(p, _mm256_cvtpd_ps(v));
#else
  for (int i = 0; i < 4; ++i) p[i] = static_cast<float>(v[i]);
#endif
}

/// Four nodes' coordinates, given as twelve doubles in three lanes (x₀ y₀ z₀ x₁ | y₁ z₁ x₂ y₂ |
/// z₂ x₃ y₃ z₃), rounded to single precision into the padded layout of four floats per node
/// (x y z 0) at p (16 floats).
inline void store_four_nodes_single(float* p, Lanes a, Lanes b, Lanes c) {
#if defined(__AVX__)
  const __m128 f0 = _mm256_cvtpd_ps(a), f1 = _mm256_cvtpd_ps(b), f2 = _mm256_cvtpd_ps(c);
  const __m128 zero = _mm_setzero_ps();
  const __m128 n1 = _mm_shuffle_ps(f0, f1, _MM_SHUFFLE(1, 0, 3, 3));  // x₁ x₁ y₁ z₁
  _mm_storeu_ps(p, _mm_blend_ps(f0, zero, 0x8));
  _mm_storeu_ps(p + 4, _mm_blend_ps(_mm_shuffle_ps(n1, n1, _MM_SHUFFLE(3, 3, 2, 0)), zero, 0x8));
  _mm_storeu_ps(p + 8, _mm_blend_ps(_mm_shuffle_ps(f1, f2, _MM_SHUFFLE(0, 0, 3, 2)), zero, 0x8));
  _mm_storeu_ps(p + 12, _mm_blend_ps(_mm_shuffle_ps(f2, f2, _MM_SHUFFLE(3, 3, 2, 1)), zero, 0x8));
#else
  const double in[12] = {a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3], c[0], c[1], c[2], c[3]};
  for (int node = 0; node < 4; ++node) {
    for (int q = 0; q < 3; ++q) p[4 * node + q] = static_cast<float>(in[3 * node + q]);
    p[4 * node + 3] = 0.0f;
  }
#endif
}

/// One double from memory in all four lanes (a plain load with AVX, no shuffle).
[[nodiscard]] inline Lanes broadcast(const double* p) {
#if defined(__AVX__)
  return _mm256_broadcast_sd(p);
#else
  return splat(*p);
#endif
}

// __builtin_shufflevector (constant lane indices, the second vector's lanes numbered 4 to
// 7) is spelled the same by GCC (12 and later) and clang, which has no __builtin_shuffle.

/// v with lane 3 set to zero.
[[nodiscard]] inline Lanes clear_lane3(Lanes v) { return __builtin_shufflevector(v, splat(0.0), 0, 1, 2, 4); }

/// Lanes (x_k, y_k, z_k, 0) of element k from the x, y, z lanes of four elements: the 4x4
/// transpose, for storing per-element vectors with whole-register writes.
inline void transpose_xyz(Lanes x, Lanes y, Lanes z, Lanes out[4]) {
  const Lanes zero = splat(0.0);
  const Lanes xy_even = __builtin_shufflevector(x, y, 0, 4, 2, 6);     // x0 y0 x2 y2
  const Lanes xy_odd = __builtin_shufflevector(x, y, 1, 5, 3, 7);      // x1 y1 x3 y3
  const Lanes z0_even = __builtin_shufflevector(z, zero, 0, 4, 2, 6);  // z0 0 z2 0
  const Lanes z0_odd = __builtin_shufflevector(z, zero, 1, 5, 3, 7);   // z1 0 z3 0
  out[0] = __builtin_shufflevector(xy_even, z0_even, 0, 1, 4, 5);
  out[1] = __builtin_shufflevector(xy_odd, z0_odd, 0, 1, 4, 5);
  out[2] = __builtin_shufflevector(xy_even, z0_even, 2, 3, 6, 7);
  out[3] = __builtin_shufflevector(xy_odd, z0_odd, 2, 3, 6, 7);
}

}  // namespace hof::mechanics::simd

#pragma GCC diagnostic pop
