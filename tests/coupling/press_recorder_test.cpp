// Presses recorded from haptic samples (press_recorder.h), fed by hand against a rigid box's
// surface (its rest points are where it is): a linear force-indentation curve gives back its
// stiffness, unloading is left out of the loading curve, a short loss of contact does not end
// a press and a long one does.

#include "hof/coupling/press_recorder.h"

#include <gtest/gtest.h>

#include <memory>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"

#include "support/box_surface.h"

namespace hof::coupling {
namespace {

// A rigid 4 cm box with its top face at y = 0 (the stylus device is never run).
std::unique_ptr<Session> box_session() {
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "box";
  bodies[0].surface = hof::testing::box_surface(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  auto scripted = haptics::ScriptedMotion::make(
      haptics::MotionConfig::poke(Vec3(0, 0.05, 0), Vec3(0, -1, 0), 0.01, 0.0, 0.05, 0.1));
  EXPECT_TRUE(scripted);
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.pin_threads = false;
  auto session = Session::make(std::move(bodies),
                               std::make_unique<haptics::ScriptedDevice>(*scripted, haptics::DeviceSpec{}), config);
  EXPECT_TRUE(session) << session.error().to_string();
  return std::move(*session);
}

// A sample in contact with triangle 0 at time `t`, the contact `depth` below the triangle's
// rest point along its inward normal, pushing with `force_n`.
haptics::HapticSample pressing(const Session& session, double t, double depth, double force_n) {
  haptics::HapticSample s;
  s.valid = true;
  s.time_s = t;
  s.contact = true;
  s.triangle = 0;
  s.layer = 0;
  s.barycentric = Vec3(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0);
  s.contact_normal = Vec3(0, 1, 0);
  s.contact_point = session.rest_point(0, s.barycentric) - depth * s.contact_normal;
  s.force = Vec3(0, force_n, 0);
  return s;
}

haptics::HapticSample clear(double t) {
  haptics::HapticSample s;
  s.valid = true;
  s.time_s = t;
  return s;
}

TEST(PressRecorder, ALinearLoadingCurveGivesItsStiffness) {
  auto session = box_session();
  PressRecorder recorder(*session);
  const double k = 250.0, w = PressRecorder::kBinWidthM;
  // The press begins at the surface (indentation is measured from there), then one sample at
  // each bin's centre (the fit takes bin means at bin centres), to 5 mm.
  EXPECT_EQ(recorder.add(pressing(*session, 0.0, 0.0, 0.0)), 0.0);
  double t = 0.001;
  for (int b = 0; b < 10; ++b) {
    const double d = (b + 0.5) * w;
    EXPECT_NEAR(recorder.add(pressing(*session, t, d, k * d)), d, 1e-12);
    t += 0.001;
  }
  ASSERT_EQ(recorder.presses().size(), 1u);
  EXPECT_EQ(recorder.current(), 1);
  const Press& p = recorder.presses()[0];
  EXPECT_EQ(p.index, 1);
  EXPECT_EQ(p.body, 0);
  EXPECT_NEAR(p.stiffness, k, 1e-9 * k);
  EXPECT_NEAR(p.max_force_n, k * 9.5 * w, 1e-12);
  EXPECT_NEAR(p.indentation_at_max_force, 9.5 * w, 1e-12);
  EXPECT_NEAR(recorder.force_at(p, 2.5 * w), k * 2.5 * w, 1e-12);
  EXPECT_EQ(recorder.force_at(p, 40.0 * w), -1.0) << "no sample there";
  EXPECT_EQ(recorder.force_at(p, -w), -1.0);

  // Unloading (the indentation no longer growing) at a lower force leaves the loading curve as it was.
  for (int b = 9; b >= 0; --b) {
    recorder.add(pressing(*session, t, (b + 0.25) * w, 0.5 * k * (b + 0.25) * w));
    t += 0.001;
  }
  EXPECT_NEAR(recorder.presses()[0].stiffness, k, 1e-9 * k);
  EXPECT_NEAR(recorder.force_at(recorder.presses()[0], 2.5 * w), k * 2.5 * w, 1e-12);
}

TEST(PressRecorder, AShortLossOfContactContinuesThePressALongOneEndsIt) {
  auto session = box_session();
  PressRecorder recorder(*session);
  recorder.add(pressing(*session, 0.0, 0.001, 0.1));
  EXPECT_EQ(recorder.add(clear(0.1)), 0.0);
  recorder.add(pressing(*session, 0.1 + 0.5 * PressRecorder::kGapS, 0.002, 0.2));
  ASSERT_EQ(recorder.presses().size(), 1u) << "a flicker shorter than kGapS";
  EXPECT_NEAR(recorder.presses()[0].max_indentation_m, 0.001, 1e-12) << "measured from the first contact";

  const double later = 0.1 + 0.5 * PressRecorder::kGapS + 2.0 * PressRecorder::kGapS;
  recorder.add(clear(later));
  EXPECT_EQ(recorder.current(), 0) << "clear for longer than kGapS: the press has ended";
  // The next press measures from where the surface is when it begins.
  EXPECT_NEAR(recorder.add(pressing(*session, later + 0.01, 0.003, 0.3)), 0.0, 1e-12);
  EXPECT_NEAR(recorder.add(pressing(*session, later + 0.02, 0.004, 0.4)), 0.001, 1e-12);
  ASSERT_EQ(recorder.presses().size(), 2u);
  EXPECT_EQ(recorder.presses()[1].index, 2);
  EXPECT_EQ(recorder.current(), 2);
  EXPECT_NEAR(recorder.presses()[0].end_s, 0.1 + 0.5 * PressRecorder::kGapS, 1e-12);
}

TEST(PressRecorder, InvalidSamplesAndContactsWithoutATriangleAreNotPresses) {
  auto session = box_session();
  PressRecorder recorder(*session);
  haptics::HapticSample invalid = pressing(*session, 0.0, 0.001, 0.1);
  invalid.valid = false;
  EXPECT_EQ(recorder.add(invalid), 0.0);
  haptics::HapticSample no_triangle = pressing(*session, 0.0, 0.001, 0.1);
  no_triangle.triangle = -1;
  EXPECT_EQ(recorder.add(no_triangle), 0.0);
  EXPECT_TRUE(recorder.presses().empty());
}

}  // namespace
}  // namespace hof::coupling
