#include "hof/mesh/surface_strain.h"

#include <cmath>

namespace hof::mesh {

double triangle_green_strain(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                             const Vec3& b2) {
  // Edge metrics G = DᵀD of the rest and current edge matrices D = [p1 − p0, p2 − p0].
  const Vec3 r1 = a1 - a0, r2 = a2 - a0, c1 = b1 - b0, c2 = b2 - b0;
  Eigen::Matrix2d g0, g;
  g0 << r1.dot(r1), r1.dot(r2), r1.dot(r2), r2.dot(r2);
  g << c1.dot(c1), c1.dot(c2), c1.dot(c2), c2.dot(c2);
  const double det0 = g0.determinant();
  if (!(det0 > 1e-30 * g0.trace() * g0.trace())) return 0.0;
  const Eigen::Matrix2d e = 0.5 * g0.inverse() * (g - g0);
  // Similar to a symmetric matrix: real eigenvalues λ = tr/2 ± √(tr²/4 − det).
  const double half_trace = 0.5 * e.trace();
  const double root = std::sqrt(std::max(half_trace * half_trace - e.determinant(), 0.0));
  const double hi = half_trace + root, lo = half_trace - root;
  return std::abs(hi) >= std::abs(lo) ? hi : lo;
}

void vertex_strain_magnitude(std::span<const Vec3> rest, std::span<const Vec3> current, std::span<const Tri> triangles,
                             std::vector<double>& out) {
  out.assign(current.size(), 0.0);
  std::vector<int> count(current.size(), 0);
  if (rest.size() != current.size()) return;
  for (const Tri& t : triangles) {
    const auto i = static_cast<std::size_t>(t[0]), j = static_cast<std::size_t>(t[1]),
               k = static_cast<std::size_t>(t[2]);
    if (i >= rest.size() || j >= rest.size() || k >= rest.size()) continue;
    const double e = std::abs(triangle_green_strain(rest[i], rest[j], rest[k], current[i], current[j], current[k]));
    for (const std::size_t v : {i, j, k}) {
      out[v] += e;
      ++count[v];
    }
  }
  for (std::size_t v = 0; v < out.size(); ++v) {
    if (count[v]) out[v] /= count[v];
  }
}

}  // namespace hof::mesh
