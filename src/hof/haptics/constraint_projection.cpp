#include "hof/haptics/constraint_projection.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace hof::haptics {

namespace {

constexpr double kFeasibilityTolerance = 1e-12;

bool feasible(const Vec3& x, const std::array<HalfSpace, 3>& planes, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    if (planes[i].normal.dot(x) < planes[i].offset - kFeasibilityTolerance) return false;
  }
  return true;
}

}  // namespace

Vec3 project_onto_half_spaces(const Vec3& goal, const std::array<HalfSpace, 3>& planes, std::size_t count,
                              const Vec3& fallback) {
  if (feasible(goal, planes, count)) return goal;
  Vec3 best = fallback;
  double best_distance = std::numeric_limits<double>::infinity();
  // Active sets as bit masks over the planes: x = goal + Σ λ_i n_i with n_i·x = c_i for i in
  // the set (a Gram system of size 1–3). Singular sets (parallel planes) are skipped.
  for (unsigned mask = 1; mask < (1u << count); ++mask) {
    std::array<std::size_t, 3> index{};
    int size = 0;
    for (std::size_t i = 0; i < count; ++i) {
      if (mask & (1u << i)) index[static_cast<std::size_t>(size++)] = i;
    }
    Eigen::Matrix3d gram = Eigen::Matrix3d::Identity();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int a = 0; a < size; ++a) {
      for (int b = 0; b < size; ++b) gram(a, b) = planes[index[a]].normal.dot(planes[index[b]].normal);
      rhs[a] = planes[index[a]].offset - planes[index[a]].normal.dot(goal);
    }
    Vec3 x = goal;
    if (size == 1) {
      x += rhs[0] * planes[index[0]].normal;
    } else if (size == 2) {
      // Fixed-size solves: this runs in the haptic tick and must not allocate.
      const Eigen::Matrix2d g = gram.topLeftCorner<2, 2>();
      const double det = g.determinant();
      if (!(std::abs(det) > 1e-10)) continue;
      const Eigen::Vector2d lambda = g.inverse() * rhs.head<2>();
      x += lambda[0] * planes[index[0]].normal + lambda[1] * planes[index[1]].normal;
    } else {
      const double det = gram.determinant();
      if (!(std::abs(det) > 1e-10)) continue;
      const Eigen::Vector3d lambda = gram.inverse() * rhs;
      for (int a = 0; a < 3; ++a) x += lambda[a] * planes[index[a]].normal;
    }
    if (!x.allFinite() || !feasible(x, planes, count)) continue;
    const double distance = (x - goal).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = x;
    }
  }
  return best;
}

}  // namespace hof::haptics
