// Tests of the scripted motions and device (device_backends/scripted_device.cpp): analytic
// properties of poke, press-and-slide, palpate, circle and hold, the stop force, invalid
// configurations, the duration and repeats.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "hof/haptics/device_backends/scripted_device.h"

namespace hof::haptics {
namespace {

ScriptedMotion make_motion(const MotionConfig& config) {
  auto m = ScriptedMotion::make(config);
  EXPECT_TRUE(m) << m.error().to_string();
  return *m;
}

TEST(ScriptedMotion, PokeReachesExactlyTheDepth) {
  MotionConfig c;  // defaults: start (0, 0.05, 0), down, depth 2 cm, 1 cm/s, hold 1 s
  const ScriptedMotion m = make_motion(c);
  EXPECT_NEAR((m.contact_point() - Vec3::Zero()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((m.deepest_point() - Vec3(0, -0.02, 0)).norm(), 0.0, 1e-15);
  // 7 cm in, 1 s hold, 7 cm out at 1 cm/s.
  EXPECT_NEAR(m.duration(), 15.0, 1e-12);
  double deepest = -1.0;
  for (double t = 0.0; t <= m.duration(); t += 1e-3) deepest = std::max(deepest, -m.position(t).y());
  EXPECT_NEAR(deepest, c.depth_m, 1e-12);
  EXPECT_NEAR((m.position(7.5) - m.deepest_point()).norm(), 0.0, 1e-15);  // mid-hold
  EXPECT_EQ(m.velocity(7.5), Vec3::Zero());
  EXPECT_NEAR((m.position(15.0) - c.start_m).norm(), 0.0, 1e-15);

  c.approach_m = 0.01;
  c.depth_m = 0.005;
  const ScriptedMotion shallow = make_motion(c);
  EXPECT_NEAR(shallow.deepest_point().y(), 0.05 - 0.015, 1e-15);
}

// A poke with force=F presses as a hand pressing to a force: against a wall of 1000 N/m at the
// contact plane it stops where the wall pushes back by F (not at its depth), holds there and
// retracts; a force larger than F makes it give way.
TEST(ScriptedMotion, APokeWithAStopForceStopsWhereItFeelsItAndGivesWay) {
  MotionConfig c;  // start (0, 0.05, 0), down, approach 5 cm, depth 2 cm, 1 cm/s, hold 1 s
  c.stop_force_n = 4.0;
  ScriptedDevice device(make_motion(c));
  const double k = 1000.0;  // N/m, a wall at y = 0
  double deepest = 0.0, last_y = 0.05;
  double held_since = -1.0;
  for (double t = 0.0; t < 20.0; t += 1e-3) {
    const DeviceReading r = device.read(t);
    if (!r.valid) break;
    const double penetration = std::max(0.0, -r.position_m.y());
    deepest = std::max(deepest, penetration);
    if (held_since < 0.0 && t > 5.1 && std::abs(r.position_m.y() - last_y) < 1e-12) held_since = t;
    last_y = r.position_m.y();
    device.write_force(Vec3(0, k * penetration, 0), Vec3::Zero());
  }
  // Stopped at F / k = 4 mm (within one reading's travel, 10 µm), far short of 2 cm.
  EXPECT_NEAR(deepest, 4.0 / k, 1.1e-5);
  EXPECT_GT(held_since, 5.3);
  EXPECT_LT(held_since, 5.5);
  EXPECT_EQ(device.health(), DeviceHealth::kEnded);  // the whole poke played, shorter
  // Giving way: a force above F pushes the device back along it by the excess over its stiffness.
  MotionConfig still = c;
  still.start_m = Vec3(0, 0.0, 0);
  still.approach_m = 0.0;
  ScriptedDevice yielding(make_motion(still));
  const Vec3 before = yielding.read(0.0).position_m;
  yielding.write_force(Vec3(0, 6.0, 0), Vec3::Zero());
  const Vec3 after = yielding.read(0.001).position_m;
  const double stiffness = yielding.spec().max_stiffness_n_per_m;
  EXPECT_NEAR((after - before).y(), (6.0 - 4.0) / stiffness - 0.01 * 0.001, 1e-12);
  // A force= on anything but one poke is refused.
  MotionConfig circle;
  circle.kind = MotionKind::kCircle;
  circle.stop_force_n = 1.0;
  EXPECT_FALSE(ScriptedMotion::make(circle));
  c.repeat = 2;
  EXPECT_FALSE(ScriptedMotion::make(c));
}

/// Positions are continuous (no jump beyond the top speed) and the analytic velocity is the
/// derivative wherever the path is smooth (checked by central differences away from corners).
void check_continuity_and_velocity(const ScriptedMotion& m, double top_speed, double t_end) {
  const double h = 1e-5;
  int smooth = 0;
  for (double t = 0.0; t < t_end; t += 0.0137) {
    const Vec3 p0 = m.position(t - h);
    const Vec3 p1 = m.position(t);
    const Vec3 p2 = m.position(t + h);
    EXPECT_LE((p1 - p0).norm(), top_speed * h * (1 + 1e-6) + 1e-15) << "jump at t = " << t;
    const Vec3 backward = (p1 - p0) / h;
    const Vec3 forward = (p2 - p1) / h;
    if ((backward - forward).norm() > 1e-3 * (1 + top_speed)) continue;  // a corner
    ++smooth;
    EXPECT_NEAR((m.velocity(t) - (p2 - p0) / (2 * h)).norm(), 0.0, 1e-6 * (1 + top_speed)) << "t = " << t;
  }
  EXPECT_GT(smooth, 10);
}

TEST(ScriptedMotion, ContinuousWithVelocityAsDerivative) {
  MotionConfig poke;
  check_continuity_and_velocity(make_motion(poke), poke.speed_m_per_s, 16.0);

  MotionConfig slide;
  slide.kind = MotionKind::kPressAndSlide;
  slide.slide_speed_m_per_s = 0.03;
  check_continuity_and_velocity(make_motion(slide), 0.03, 30.0);

  MotionConfig circle;
  circle.kind = MotionKind::kCircle;
  circle.repeat = 3;
  const ScriptedMotion m = make_motion(circle);
  const double speed = 2 * std::numbers::pi * circle.radius_m / circle.period_s;
  check_continuity_and_velocity(m, speed, m.duration());
  for (double t = 0.0; t < m.duration(); t += 0.1) {
    EXPECT_NEAR((m.position(t) - circle.centre_m).norm(), circle.radius_m, 1e-15);
    EXPECT_NEAR(m.position(t).y(), 0.0, 1e-15);  // in the plane normal to y
  }
}

TEST(ScriptedMotion, PressAndSlideSlidesTangentially) {
  MotionConfig c;
  c.kind = MotionKind::kPressAndSlide;
  c.slide_direction = Vec3(1.0, 1.0, 0.0);  // tilted: only its tangential part counts
  const ScriptedMotion m = make_motion(c);
  double farthest = 0.0;
  for (double t = 0.0; t < m.duration(); t += 1e-3) {
    const Vec3 p = m.position(t);
    if (std::abs(p.y() - m.deepest_point().y()) < 1e-12) farthest = std::max(farthest, p.x());
    EXPECT_NEAR(p.z(), 0.0, 1e-15);
  }
  EXPECT_NEAR(farthest, c.slide_distance_m, 1e-5);
  EXPECT_NEAR((m.position(m.duration()) - c.start_m).norm(), 0.0, 1e-15);
}

TEST(ScriptedMotion, PalpateSweepsPressesAlongTheStep) {
  MotionConfig c;
  c.kind = MotionKind::kPalpate;
  c.start_m = Vec3(0.0, 0.05, 0.0);
  c.direction = Vec3(0, -1, 0);
  c.approach_m = 0.02;
  c.depth_m = 0.01;
  c.hold_s = 0.5;
  c.palpation_step_m = Vec3(0.02, 0.0, 0.0);
  c.palpation_count = 3;
  const ScriptedMotion m = make_motion(c);
  // Per press: 3 cm down, hold, 3 cm up, 2 cm across (not after the last) at 1 cm/s.
  EXPECT_NEAR(m.duration(), 3 * (3.0 + 0.5 + 3.0) + 2 * 2.0, 1e-9);
  // Each press reaches its deepest point, 2 cm further along x than the one before.
  std::vector<double> deepest_x;
  bool down = false;
  for (double t = 0.0; t <= m.duration(); t += 1e-3) {
    const Vec3 p = m.position(t);
    const bool at_depth = std::abs(p.y() - 0.02) < 1e-9;
    if (at_depth && !down) deepest_x.push_back(p.x());
    down = at_depth;
    EXPECT_GE(p.y(), 0.02 - 1e-12);  // never deeper than asked
  }
  ASSERT_EQ(deepest_x.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(deepest_x[k], 0.02 * static_cast<double>(k), 1e-9);
  EXPECT_NEAR((m.position(m.duration()) - Vec3(0.04, 0.05, 0.0)).norm(), 0.0, 1e-12);  // the last start
  // Repeated sweeps travel back (continuous), not jump.
  c.repeat = 2;
  const ScriptedMotion twice = make_motion(c);
  for (double t = 0.0; t + 1e-3 <= twice.duration(); t += 1e-3) {
    EXPECT_LT((twice.position(t + 1e-3) - twice.position(t)).norm(), 1.1e-5) << t;
  }
}

TEST(ScriptedMotion, RejectsBadConfigs) {
  MotionConfig c;
  c.speed_m_per_s = 0.0;
  auto m = ScriptedMotion::make(c);
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("speed must be > 0"), std::string::npos);
  c = MotionConfig{};
  c.direction = Vec3::Zero();
  EXPECT_FALSE(ScriptedMotion::make(c));
  c = MotionConfig{};
  c.kind = MotionKind::kPressAndSlide;
  c.slide_direction = Vec3(0, 2, 0);  // parallel to the press
  EXPECT_FALSE(ScriptedMotion::make(c));
  c = MotionConfig{};
  c.kind = MotionKind::kCircle;
  c.period_s = -1;
  EXPECT_FALSE(ScriptedMotion::make(c));
}

TEST(ScriptedDevice, EndsAfterItsDurationUnlessRepeated) {
  MotionConfig c;
  ScriptedDevice once(make_motion(c));
  EXPECT_TRUE(once.read(15.0).valid);
  EXPECT_EQ(once.health(), DeviceHealth::kOk);
  EXPECT_FALSE(once.read(15.001).valid);
  EXPECT_EQ(once.health(), DeviceHealth::kEnded);

  c.repeat = 0;  // forever
  ScriptedDevice forever(make_motion(c));
  for (const double t : {3.0, 8.0, 14.0}) {
    const DeviceReading a = forever.read(t);
    const DeviceReading b = forever.read(t + 15.0 * 40);
    EXPECT_TRUE(b.valid);
    EXPECT_NEAR((a.position_m - b.position_m).norm(), 0.0, 1e-12);
  }
  EXPECT_EQ(forever.health(), DeviceHealth::kOk);
}

}  // namespace
}  // namespace hof::haptics
