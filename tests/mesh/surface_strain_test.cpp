// Membrane strain of a deformed surface (src/hof/mesh/surface_strain.cpp): the Green strain
// (λ² − 1)/2 of a stretch, signed, the larger in magnitude of the two principal strains, zero
// under rigid motion whatever the triangle, and per-vertex means.

#include "hof/mesh/surface_strain.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

namespace hof::mesh {
namespace {

const Vec3 kA0(0, 0, 0), kA1(1, 0, 0), kA2(0, 1, 0);

// The rest triangle deformed by the in-plane map (x, y) → F (x, y).
double strain_of(const Eigen::Matrix2d& f) {
  const auto map = [&](const Vec3& p) {
    const Eigen::Vector2d q = f * Eigen::Vector2d(p.x(), p.y());
    return Vec3(q.x(), q.y(), 0.0);
  };
  return triangle_green_strain(kA0, kA1, kA2, map(kA0), map(kA1), map(kA2));
}

TEST(TriangleGreenStrain, AStretchGivesHalfOfLambdaSquaredMinusOneSigned) {
  EXPECT_NEAR(strain_of(Eigen::Vector2d(1.2, 1.0).asDiagonal()), 0.5 * (1.44 - 1.0), 1e-14);  // stretched
  EXPECT_NEAR(strain_of(Eigen::Vector2d(0.8, 1.0).asDiagonal()), 0.5 * (0.64 - 1.0), 1e-14);  // compressed
  // Both: the one of larger magnitude wins, with its sign.
  EXPECT_NEAR(strain_of(Eigen::Vector2d(1.1, 0.7).asDiagonal()), 0.5 * (0.49 - 1.0), 1e-14);
  EXPECT_NEAR(strain_of(Eigen::Vector2d(1.3, 0.9).asDiagonal()), 0.5 * (1.69 - 1.0), 1e-14);
  EXPECT_EQ(strain_of(Eigen::Matrix2d::Identity()), 0.0);
}

TEST(TriangleGreenStrain, SimpleShearHasTheAnalyticPrincipalStrain) {
  // F = [1 g; 0 1]: E = ½ [0 g; g g²], eigenvalues g²/4 ± √(g⁴/16 + g²/4).
  const double g = 0.2;
  Eigen::Matrix2d f;
  f << 1.0, g, 0.0, 1.0;
  EXPECT_NEAR(strain_of(f), g * g / 4 + std::sqrt(g * g * g * g / 16 + g * g / 4), 1e-14);
}

TEST(TriangleGreenStrain, RigidMotionIsNoStrainAndTheTrianglesPoseDoesNotMatter) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 a0(u(rng), u(rng), u(rng)), a1(u(rng), u(rng), u(rng)), a2(u(rng), u(rng), u(rng));
    if ((a1 - a0).cross(a2 - a0).norm() < 1e-2) continue;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    const Vec3 shift(u(rng), u(rng), u(rng));
    EXPECT_NEAR(triangle_green_strain(a0, a1, a2, r * a0 + shift, r * a1 + shift, r * a2 + shift), 0.0, 1e-12);
    // A stretch by 1.25 along an in-plane direction, then the rigid motion: (1.25² − 1)/2.
    const Vec3 d = (a1 - a0).normalized();
    const Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity() + 0.25 * d * d.transpose();
    const auto moved = [&](const Vec3& p) { return Vec3(r * (stretch * (p - a0)) + shift); };
    EXPECT_NEAR(triangle_green_strain(a0, a1, a2, moved(a0), moved(a1), moved(a2)), 0.5 * (1.5625 - 1.0), 1e-10);
  }
}

TEST(TriangleGreenStrain, ADegenerateRestTriangleHasNoStrain) {
  EXPECT_EQ(triangle_green_strain(kA0, kA1, Vec3(2, 0, 0), kA0, Vec3(3, 0, 0), Vec3(0, 1, 0)), 0.0);
  EXPECT_EQ(triangle_green_strain(kA0, kA0, kA0, kA0, kA1, kA2), 0.0);
}

TEST(VertexStrainMagnitude, IsTheMeanMagnitudeOverAVertexsTriangles) {
  // A unit square of two triangles; vertex 2 pulled out along x: triangle (0, 1, 2) and
  // (0, 2, 3) strain differently, vertices 1 and 3 see one triangle each, 0 and 2 both.
  const std::vector<Vec3> rest{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  std::vector<Vec3> now = rest;
  now[1] = Vec3(0.5, 0, 0);  // compresses the first triangle only
  const std::vector<Tri> triangles{{0, 1, 2}, {0, 2, 3}};
  const double e0 = std::abs(triangle_green_strain(rest[0], rest[1], rest[2], now[0], now[1], now[2]));
  const double e1 = std::abs(triangle_green_strain(rest[0], rest[2], rest[3], now[0], now[2], now[3]));
  ASSERT_GT(e0, 0.1);
  ASSERT_EQ(e1, 0.0);
  std::vector<double> out;
  vertex_strain_magnitude(rest, now, triangles, out);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_DOUBLE_EQ(out[0], 0.5 * e0);
  EXPECT_DOUBLE_EQ(out[1], e0);
  EXPECT_DOUBLE_EQ(out[2], 0.5 * e0);
  EXPECT_EQ(out[3], 0.0);
  // Shapes that do not match, or triangles past the vertices: zeros, no crash.
  vertex_strain_magnitude(rest, std::vector<Vec3>(3, Vec3::Zero()), triangles, out);
  EXPECT_EQ(out, std::vector<double>(3, 0.0));
  vertex_strain_magnitude(rest, now, std::vector<Tri>{{0, 1, 9}}, out);
  EXPECT_EQ(out, std::vector<double>(4, 0.0));
}

}  // namespace

TEST(SurfaceStrain, MatchesTheAnalyticGreenStrainOfStretchesAndIsZeroForRigidMotions) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // A stretch by 1.2 along x: E_xx = (1.2² − 1) / 2 = 0.22 (the larger principal strain).
  EXPECT_NEAR(triangle_green_strain(a, b, c, a, Vec3(1.2, 0, 0), c), 0.22, 1e-12);
  // Compression by 0.9 along y: E_yy = (0.81 − 1) / 2 = −0.095, signed.
  EXPECT_NEAR(triangle_green_strain(a, b, c, a, b, Vec3(0, 0.9, 0)), -0.095, 1e-12);
  // Rotated and moved, not deformed: no strain.
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 t(0.3, -2, 5);
  EXPECT_NEAR(triangle_green_strain(a, b, c, r * a + t, r * b + t, r * c + t), 0.0, 1e-12);
  // A degenerate rest triangle gives 0, not NaN.
  EXPECT_EQ(triangle_green_strain(a, b, Vec3(2, 0, 0), a, b, c), 0.0);
  // Per vertex: the mean of its triangles' magnitudes.
  const std::vector<Vec3> rest{a, b, c, Vec3(1, 1, 0)};
  std::vector<Vec3> now = rest;
  now[1].x() = 1.2;
  std::vector<double> strain;
  vertex_strain_magnitude(rest, now, std::vector<Tri>{{0, 1, 2}, {1, 3, 2}}, strain);
  ASSERT_EQ(strain.size(), 4u);
  EXPECT_NEAR(strain[0], 0.22, 1e-12);
  EXPECT_GT(strain[3], 0.0);
}

}  // namespace hof::mesh
