// The proxy's target under up to three half-space constraints
// (src/hof/haptics/constraint_projection.cpp): analytic projections onto one, two and three
// planes, the goal kept when feasible, the fallback when nothing is, and on random sets of
// planes the optimality condition of a projection onto a convex set.

#include "hof/haptics/constraint_projection.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <random>

namespace hof::haptics {
namespace {

HalfSpace plane(const Vec3& normal, double offset) { return HalfSpace{normal.normalized(), offset}; }

const Vec3 kFallback(7, 7, 7);

TEST(ProjectOntoHalfSpaces, AFeasibleGoalOrNoPlaneKeepsTheGoal) {
  const std::array<HalfSpace, 3> planes{plane(Vec3::UnitZ(), 0.0), plane(Vec3::UnitX(), -1.0), HalfSpace{}};
  EXPECT_EQ(project_onto_half_spaces(Vec3(1, 2, 3), planes, 2, kFallback), Vec3(1, 2, 3));
  EXPECT_EQ(project_onto_half_spaces(Vec3(1, 2, -3), planes, 0, kFallback), Vec3(1, 2, -3));
  EXPECT_EQ(project_onto_half_spaces(Vec3(1, 2, 0), planes, 1, kFallback), Vec3(1, 2, 0));  // on the plane
}

TEST(ProjectOntoHalfSpaces, OntoOneTwoAndThreePlanes) {
  // One: z ≥ 0.5.
  std::array<HalfSpace, 3> planes{plane(Vec3::UnitZ(), 0.5), plane(Vec3::UnitX(), 0.0), plane(Vec3::UnitY(), 0.0)};
  EXPECT_LT((project_onto_half_spaces(Vec3(1, 2, -3), planes, 1, kFallback) - Vec3(1, 2, 0.5)).norm(), 1e-15);
  // Two, orthogonal: the edge x = 0, z = 0.5.
  EXPECT_LT((project_onto_half_spaces(Vec3(-1, 5, -2), planes, 2, kFallback) - Vec3(0, 5, 0.5)).norm(), 1e-15);
  // Two, but only one active: below z, in front of x.
  EXPECT_LT((project_onto_half_spaces(Vec3(3, 5, -2), planes, 2, kFallback) - Vec3(3, 5, 0.5)).norm(), 1e-15);
  // Three: the corner.
  EXPECT_LT((project_onto_half_spaces(Vec3(-1, -2, -3), planes, 3, kFallback) - Vec3(0, 0, 0.5)).norm(), 1e-15);
  // A 90°+ wedge: z ≥ 0 and the plane through the x axis tilted 45° (y + z ≥ 0). Below both,
  // under the edge: the edge itself.
  planes = {plane(Vec3::UnitZ(), 0.0), plane(Vec3(0, 1, 1), 0.0), HalfSpace{}};
  EXPECT_LT((project_onto_half_spaces(Vec3(2, -0.1, -1), planes, 2, kFallback) - Vec3(2, 0, 0)).norm(), 1e-15);
}

TEST(ProjectOntoHalfSpaces, PlanesThatCannotAllBeMetGiveTheFallback) {
  const std::array<HalfSpace, 3> planes{plane(Vec3::UnitZ(), 1.0), plane(-Vec3::UnitZ(), 0.0),
                                        HalfSpace{}};  // z ≥ 1, z ≤ 0
  EXPECT_EQ(project_onto_half_spaces(Vec3(0, 0, 0.5), planes, 2, kFallback), kFallback);
}

TEST(ProjectOntoHalfSpaces, IsTheProjectionOntoTheConvexSetOnRandomPlanes) {
  std::mt19937 rng(17);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  // Draws one at a time: the order in which a constructor's arguments are evaluated is
  // unspecified (GCC and clang differ), and the sequence must be the same on every compiler.
  const auto draw = [&rng](auto& distribution) {
    const double a = distribution(rng);
    const double b = distribution(rng);
    const double c = distribution(rng);
    return Vec3(a, b, c);
  };
  int projected = 0;
  int nearly_dependent = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t count = 1 + static_cast<std::size_t>(trial % 3);
    std::array<HalfSpace, 3> planes{};
    Eigen::Matrix3d normals = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < count; ++i) {
      const Vec3 n = draw(normal);
      planes[i] = plane(n, 0.3 * uniform(rng));
      normals.row(static_cast<Eigen::Index>(i)) = planes[i].normal.transpose();
    }
    const Vec3 goal = draw(uniform);
    // Up to three half-spaces with linearly independent normals always meet. Nearly dependent
    // normals put the corner arbitrarily far away, where the projection's own tolerance on a
    // singular active set rightly gives up: those draws are skipped (and counted).
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(normals);
    if (svd.singularValues()[static_cast<Eigen::Index>(count) - 1] < 0.05) {
      ++nearly_dependent;
      continue;
    }
    const Vec3 x = project_onto_half_spaces(goal, planes, count, kFallback);
    ASSERT_NE(x, kFallback) << "trial " << trial;
    for (std::size_t i = 0; i < count; ++i) ASSERT_GE(planes[i].normal.dot(x), planes[i].offset - 1e-12);
    if (x != goal) ++projected;
    // x is the projection iff (goal − x)·(y − x) ≤ 0 for every feasible y.
    for (int k = 0; k < 200; ++k) {
      const Vec3 y = x + Vec3(uniform(rng), uniform(rng), uniform(rng));
      bool feasible = true;
      for (std::size_t i = 0; i < count; ++i) feasible &= planes[i].normal.dot(y) >= planes[i].offset;
      if (feasible) {
        ASSERT_LE((goal - x).dot(y - x), 1e-12) << "trial " << trial;
      }
    }
  }
  EXPECT_GT(projected, 500);
  EXPECT_LT(nearly_dependent, 200);  // the skip must not empty the test
}

}  // namespace
}  // namespace hof::haptics
