#include "hof/mechanics/detail/vector_kernels.h"

#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/simd_lanes.h"

namespace hof::mechanics::detail {

namespace {
constexpr std::size_t kVectorChunk = 4096;
}  // namespace

// Σ a[d]·b[d] over [d0, d1) in four interleaved partial sums (independent add chains: the
// loop is not bound by the adder's latency), combined in a fixed order: deterministic.
double dot_range(const double* a, const double* b, std::size_t d0, std::size_t d1) {
  simd::Lanes sum = simd::splat(0.0);
  std::size_t d = d0;
  for (; d + 4 <= d1; d += 4) sum += simd::load(a + d) * simd::load(b + d);
  double tail = 0.0;
  for (; d < d1; ++d) tail += a[d] * b[d];
  return ((sum[0] + sum[1]) + (sum[2] + sum[3])) + tail;
}

double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b, std::vector<double>& partials) {
  const double* pa = a.data();
  const double* pb = b.data();
  return deterministic_sum(static_cast<std::size_t>(a.size()), kVectorChunk, partials,
                           [&](std::size_t begin, std::size_t end) { return dot_range(pa, pb, begin, end); });
}

void axpy(double alpha, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  const double* px = x.data();
  double* py = y.data();
  parallel_chunks(static_cast<std::size_t>(x.size()), kVectorChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) py[i] += alpha * px[i];
  });
}

void project(const MechanicalModel& model, Eigen::VectorXd& vector) {
  for (std::int32_t d : model.fixed_dofs) vector[d] = 0.0;
}

}  // namespace hof::mechanics::detail
