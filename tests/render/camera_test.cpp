// The orbit camera (src/hof/render/camera.cpp): an orthonormal right-handed frame, look() and
// fit() placing the eye where asked, the view and projection matrices against gluLookAt's and
// gluPerspective's definitions, pixels and rays inverse to each other, and the mouse gestures
// (orbit keeps the distance, pan moves the scene with the mouse, zoom clamps).

#include "hof/render/camera.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>

namespace hof::render {
namespace {

constexpr double kW = 640.0, kH = 480.0;

void expect_orthonormal_frame(const OrbitCamera& c) {
  const Vec3 f = c.forward(), r = c.right(), u = c.up_on_screen();
  EXPECT_NEAR(f.norm(), 1.0, 1e-12);
  EXPECT_NEAR(r.norm(), 1.0, 1e-12);
  EXPECT_NEAR(u.norm(), 1.0, 1e-12);
  EXPECT_NEAR(f.dot(r), 0.0, 1e-12);
  EXPECT_NEAR(f.dot(u), 0.0, 1e-12);
  EXPECT_NEAR(r.dot(u), 0.0, 1e-12);
  EXPECT_LT((r.cross(u) + f).norm(), 1e-12);  // right-handed, looking down −z of the eye frame
}

Vec3 homogeneous(const Eigen::Matrix4d& m, const Vec3& p) {
  const Eigen::Vector4d q = m * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
  return q.head<3>() / q.w();
}

TEST(OrbitCamera, TheDefaultLooksAtTheOriginFromTheFrontAndAbove) {
  const OrbitCamera c;
  expect_orthonormal_frame(c);
  EXPECT_NEAR((c.eye() - c.target()).norm(), 0.5, 1e-12);
  EXPECT_LT(c.eye().y(), 0.0);           // in front (−y) of a z-up scene
  EXPECT_GT(c.eye().z(), 0.0);           // above it
  EXPECT_GT(c.up_on_screen().z(), 0.0);  // the scene's up is up on screen
  EXPECT_NEAR(c.fov_y_rad(), 40.0 * std::numbers::pi / 180.0, 1e-15);
}

TEST(OrbitCamera, LookPutsTheEyeAndTargetWhereAsked) {
  OrbitCamera c;
  const Vec3 eye(0.3, -0.4, 0.2), target(0.1, 0.05, -0.02);
  c.look(eye, target);
  EXPECT_LT((c.eye() - eye).norm(), 1e-12);
  EXPECT_EQ(c.target(), target);
  EXPECT_NEAR(c.distance(), (eye - target).norm(), 1e-15);
  EXPECT_LT((c.forward() - (target - eye).normalized()).norm(), 1e-12);
  expect_orthonormal_frame(c);
  // Straight from above: the pitch stops short of the pole, so the frame stays defined.
  c.look(Vec3(0, 0, 2), Vec3::Zero());
  expect_orthonormal_frame(c);
  EXPECT_GT(c.forward().z(), -1.0 + 1e-6);
  EXPECT_NEAR(c.distance(), 2.0, 1e-15);
  // The eye on the target: a unit distance, a usable frame.
  c.look(Vec3(1, 1, 1), Vec3(1, 1, 1));
  EXPECT_EQ(c.distance(), 1.0);
  expect_orthonormal_frame(c);
}

TEST(OrbitCamera, ViewMapsTheEyeToTheOriginAndTheTargetDownMinusZ) {
  OrbitCamera c;
  c.look(Vec3(0.3, -0.4, 0.2), Vec3(0.1, 0.05, -0.02));
  const Eigen::Matrix4d v = c.view();
  EXPECT_LT(homogeneous(v, c.eye()).norm(), 1e-12);
  EXPECT_LT((homogeneous(v, c.target()) - Vec3(0, 0, -c.distance())).norm(), 1e-12);
  EXPECT_LT((homogeneous(v, c.eye() + c.right()) - Vec3(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((homogeneous(v, c.eye() + c.up_on_screen()) - Vec3(0, 1, 0)).norm(), 1e-12);
  // A rigid motion: the rotation block is orthonormal.
  const Mat3 r = v.block<3, 3>(0, 0);
  EXPECT_LT((r * r.transpose() - Mat3::Identity()).norm(), 1e-12);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
}

TEST(OrbitCamera, ProjectionPutsNearAndFarAtTheDepthRangeEnds) {
  OrbitCamera c;
  c.look(Vec3(0, -2, 0), Vec3::Zero());
  const double aspect = kW / kH;
  const Eigen::Matrix4d pv = c.projection(aspect) * c.view();
  const double near = 0.01 * 2.0, far = 20.0 * 2.0;
  EXPECT_NEAR(homogeneous(pv, c.eye() + near * c.forward()).z(), -1.0, 1e-9);
  EXPECT_NEAR(homogeneous(pv, c.eye() + far * c.forward()).z(), 1.0, 1e-9);
  // The target is in the middle of the screen; the edge of the vertical field of view at y = ±1.
  const Vec3 centre = homogeneous(pv, c.target());
  EXPECT_NEAR(centre.x(), 0.0, 1e-12);
  EXPECT_NEAR(centre.y(), 0.0, 1e-12);
  const double half = std::tan(0.5 * c.fov_y_rad()) * 2.0;
  EXPECT_NEAR(homogeneous(pv, c.target() + half * c.up_on_screen()).y(), 1.0, 1e-12);
  EXPECT_NEAR(homogeneous(pv, c.target() + half * aspect * c.right()).x(), 1.0, 1e-12);
}

TEST(OrbitCamera, RayAndToPixelAreInverse) {
  OrbitCamera c;
  c.look(Vec3(0.3, -0.4, 0.2), Vec3(0.1, 0.05, -0.02));
  EXPECT_LT((c.to_pixel(c.target(), kW, kH) - Vec3(kW / 2 - 0.5, kH / 2 - 0.5, c.distance())).norm(), 1e-9);
  for (const auto& [x, y] : std::array<std::array<double, 2>, 4>{{{0, 0}, {639, 479}, {100.5, 400}, {320, 17}}}) {
    const auto [origin, direction] = c.ray(x, y, kW, kH);
    EXPECT_LT((origin - c.eye()).norm(), 1e-15);
    EXPECT_NEAR(direction.norm(), 1.0, 1e-12);
    const Vec3 pixel = c.to_pixel(origin + 0.7 * direction, kW, kH);
    EXPECT_NEAR(pixel.x(), x, 1e-9);
    EXPECT_NEAR(pixel.y(), y, 1e-9);
    EXPECT_NEAR(pixel.z(), 0.7 * direction.dot(c.forward()), 1e-12);
  }
  // Right on screen is +x in pixels, up on screen is −y (rows go down).
  const Vec3 centre = c.to_pixel(c.target(), kW, kH);
  EXPECT_GT(c.to_pixel(c.target() + 0.01 * c.right(), kW, kH).x(), centre.x());
  EXPECT_LT(c.to_pixel(c.target() + 0.01 * c.up_on_screen(), kW, kH).y(), centre.y());
}

TEST(OrbitCamera, FitShowsTheWholeBox) {
  for (const Vec3& up : {Vec3(0, 0, 1), Vec3(0, 1, 0)}) {
    OrbitCamera c;
    c.set_up(up);
    const Vec3 lo(-0.1, 0.2, 0.0), hi(0.15, 0.3, 0.08);
    c.fit(lo, hi);
    EXPECT_LT((c.target() - 0.5 * (lo + hi)).norm(), 1e-15);
    EXPECT_NEAR(c.distance(), 1.15 * 0.5 * (hi - lo).norm() / std::sin(0.5 * c.fov_y_rad()), 1e-12);
    EXPECT_GT(c.up_on_screen().dot(up), 0.0);
    expect_orthonormal_frame(c);
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(), (corner & 4) ? hi.z() : lo.z());
      const Vec3 pixel = c.to_pixel(p, kW, kH);
      EXPECT_GT(pixel.z(), 0.0);
      EXPECT_GE(pixel.x(), 0.0);
      EXPECT_LE(pixel.x(), kW);
      EXPECT_GE(pixel.y(), 0.0);
      EXPECT_LE(pixel.y(), kH);
    }
  }
}

TEST(OrbitCamera, OrbitKeepsTargetAndDistanceAndNeverFlipsOverThePole) {
  OrbitCamera c;
  c.look(Vec3(0.3, -0.4, 0.2), Vec3(0.1, 0.05, -0.02));
  const Vec3 target = c.target();
  const double distance = c.distance();
  for (int i = 0; i < 50; ++i) {
    c.orbit(37.0, 91.0);  // far past straight up after a few drags
    EXPECT_EQ(c.target(), target);
    EXPECT_NEAR((c.eye() - target).norm(), distance, 1e-12);
    expect_orthonormal_frame(c);
    EXPECT_GT(c.up_on_screen().z(), 0.0);
  }
}

TEST(OrbitCamera, PanMovesTheSceneWithTheMouse) {
  OrbitCamera c;
  c.look(Vec3(0.3, -0.4, 0.2), Vec3(0.1, 0.05, -0.02));
  const Vec3 point = c.target();  // a point at the target's depth
  const Vec3 before = c.to_pixel(point, kW, kH);
  c.pan(25.0, -40.0, kH);
  const Vec3 after = c.to_pixel(point, kW, kH);
  EXPECT_NEAR(after.x() - before.x(), 25.0, 1e-9);
  EXPECT_NEAR(after.y() - before.y(), -40.0, 1e-9);
  EXPECT_NEAR(after.z(), before.z(), 1e-12);
}

TEST(OrbitCamera, ZoomScalesTheDistanceWithinItsLimits) {
  OrbitCamera c;
  c.look(Vec3(0, -1, 0), Vec3::Zero());
  c.zoom(0.5);
  EXPECT_DOUBLE_EQ(c.distance(), 0.5);
  EXPECT_LT((c.eye() - Vec3(0, -0.5, 0)).norm(), 1e-12);
  c.zoom(1e-9);
  EXPECT_EQ(c.distance(), 1e-5);
  c.zoom(1e20);
  EXPECT_EQ(c.distance(), 1e5);
}

TEST(OrbitCamera, AnyUpAxisGivesAFrameAndAZeroUpIsIgnored) {
  for (const Vec3& up : {Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(1, 2, -3).normalized()}) {
    OrbitCamera c;
    c.set_up(up);
    c.look(up + Vec3(0.3, 0.2, 0.1), Vec3::Zero());
    expect_orthonormal_frame(c);
    EXPECT_GT(c.up_on_screen().dot(up), 0.0) << up.transpose();
  }
  OrbitCamera c;
  c.set_up(Vec3::Zero());
  EXPECT_GT(c.up_on_screen().z(), 0.0);
}

}  // namespace
}  // namespace hof::render
