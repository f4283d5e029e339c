#include "hof/mesh/tet_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace hof::mesh {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(TetGeometry, UnitCornerTetVolumeAndOrientation) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
  EXPECT_DOUBLE_EQ(tet_signed_volume(a, b, c, d), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ(tet_signed_volume(a, c, b, d), -1.0 / 6.0);  // swapping two corners inverts
}

TEST(TetGeometry, RegularTetHasTextbookAnglesAndRatioOne) {
  // Regular tetrahedron inscribed in a cube: all dihedral angles acos(1/3) ≈ 70.5288°.
  const Vec3 a(1, 1, 1), b(1, -1, -1), c(-1, 1, -1), d(-1, -1, 1);
  for (double angle : tet_dihedral_angles(a, b, c, d)) {
    EXPECT_NEAR(angle, std::acos(1.0 / 3.0), 1e-12);
  }
  EXPECT_NEAR(tet_radius_ratio(a, b, c, d), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(tet_signed_volume(a, b, c, d)), 8.0 / 3.0, 1e-12);
}

TEST(TetGeometry, CornerTetAnglesAreNinetyAndSixtyAndArccos) {
  // At the right-angled corner, the three edges along the axes have 90° dihedral angles;
  // the three other edges have acos(1/sqrt(3)) ≈ 54.7356°.
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
  const auto angles = tet_dihedral_angles(a, b, c, d);
  for (int e = 0; e < 3; ++e) EXPECT_NEAR(angles[e], 90.0 * kDeg, 1e-12);
  for (int e = 3; e < 6; ++e) EXPECT_NEAR(angles[e], std::acos(1.0 / std::sqrt(3.0)), 1e-12);
}

TEST(TetGeometry, SliverHasSmallAngleAndRatio) {
  // Four nearly coplanar points: a sliver.
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 1e-3), d(0, 1, 0);
  EXPECT_LT(tet_min_dihedral_angle(a, b, c, d), 1.0 * kDeg);
  EXPECT_LT(tet_radius_ratio(a, b, c, d), 0.01);
}

TEST(TetGeometry, DegenerateTetIsZeroNotNaN) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(2, 0, 0), d(3, 0, 0);
  EXPECT_EQ(tet_radius_ratio(a, b, c, d), 0.0);
  EXPECT_FALSE(std::isnan(tet_min_dihedral_angle(a, b, c, d)));
}

}  // namespace
}  // namespace hof::mesh
