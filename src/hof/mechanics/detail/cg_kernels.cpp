#include "hof/mechanics/detail/cg_kernels.h"

#include "hof/mechanics/detail/simd_lanes.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace hof::mechanics::detail {

using simd::Lanes;

namespace {
// Lanes 0..3 added in a fixed order.
double horizontal_sum(Lanes v) { return (v[0] + v[1]) + (v[2] + v[3]); }
}  // namespace

double cg_update_solution(double* __restrict x, double* __restrict r, const double* __restrict p,
                          const double* __restrict ap, double alpha, float* __restrict r_single, std::size_t first,
                          std::size_t last) {
  const Lanes a = simd::splat(alpha);
  Lanes sum[3] = {simd::splat(0.0), simd::splat(0.0), simd::splat(0.0)};
  std::size_t node = first;
  // Four nodes (twelve doubles, three lanes) per iteration.
  for (; node + 4 <= last; node += 4) {
    const std::size_t d = 3 * node;
    Lanes new_r[3];
    for (int k = 0; k < 3; ++k) {
      new_r[k] = simd::load(r + d + 4 * k) - a * simd::load(ap + d + 4 * k);
      simd::store(r + d + 4 * k, new_r[k]);
      simd::store(x + d + 4 * k, simd::load(x + d + 4 * k) + a * simd::load(p + d + 4 * k));
      sum[k] += new_r[k] * new_r[k];
    }
    if (r_single != nullptr) simd::store_four_nodes_single(r_single + 4 * node, new_r[0], new_r[1], new_r[2]);
  }
  double tail = 0.0;
  for (; node < last; ++node) {
    for (std::size_t d = 3 * node; d < 3 * node + 3; ++d) {
      x[d] += alpha * p[d];
      r[d] -= alpha * ap[d];
      tail += r[d] * r[d];
    }
    if (r_single != nullptr) {
      for (int q = 0; q < 3; ++q) r_single[4 * node + q] = static_cast<float>(r[3 * node + q]);
      r_single[4 * node + 3] = 0.0f;
    }
  }
  return horizontal_sum((sum[0] + sum[1]) + sum[2]) + tail;
}

double cg_update_direction(double* __restrict p, double* __restrict ap, const double* __restrict z,
                           const double* __restrict az, double beta, std::size_t first, std::size_t last) {
  const Lanes b = simd::splat(beta);
  Lanes sum[3] = {simd::splat(0.0), simd::splat(0.0), simd::splat(0.0)};
  std::size_t node = first;
  for (; node + 4 <= last; node += 4) {
    const std::size_t d = 3 * node;
    for (int k = 0; k < 3; ++k) {
      const Lanes new_p = simd::load(z + d + 4 * k) + b * simd::load(p + d + 4 * k);
      const Lanes new_ap = simd::load(az + d + 4 * k) + b * simd::load(ap + d + 4 * k);
      simd::store(p + d + 4 * k, new_p);
      simd::store(ap + d + 4 * k, new_ap);
      sum[k] += new_p * new_ap;
    }
  }
  double tail = 0.0;
  for (std::size_t d = 3 * node; d < 3 * last; ++d) {
    p[d] = z[d] + beta * p[d];
    ap[d] = az[d] + beta * ap[d];
    tail += p[d] * ap[d];
  }
  return horizontal_sum((sum[0] + sum[1]) + sum[2]) + tail;
}

}  // namespace hof::mechanics::detail

#pragma GCC diagnostic pop
