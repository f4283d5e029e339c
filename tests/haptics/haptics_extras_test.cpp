// Magnetic and zero-force surfaces, force effects, and the zero-allocation haptic tick.

#include <gtest/gtest.h>

#include "support/allocation_counter.h"

#include <atomic>
#include <cstdlib>
#include <new>
#include <numbers>

#include "haptics_test_support.h"
#include "hof/haptics/haptic_loop.h"



namespace hof::haptics {
namespace {

using testing::box_surface;

SurfaceSnapshot floor_snapshot() {
  SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.2, -0.2, -0.1), Vec3(0.2, 0.2, 0.0)));
  s.is_static = true;
  return s;
}

TEST(MagneticSurface, HoldsTheProxyWithinTheSnapDistance) {
  const SurfaceSnapshot s = floor_snapshot();
  SurfaceMaterial m;
  m.kind = SurfaceKind::kMagnetic;
  m.stiffness = 1.0;
  m.static_friction = m.dynamic_friction = 0.0;
  m.snap_distance_m = 0.005;
  RendererConfig c;
  c.kind = RendererKind::kGodObject;
  HapticRenderer r(c, m, 1000.0);
  r.reset(Vec3(0, 0, 0.01));
  r.update(Vec3(0, 0, -0.002), Vec3::Zero(), s, false, 1e-3);
  ASSERT_TRUE(r.update(Vec3(0, 0, -0.002), Vec3::Zero(), s, false, 1e-3).in_contact);
  // Lifted 3 mm off the surface: still held, pulled back down.
  const ContactState& held = r.update(Vec3(0, 0, 0.003), Vec3::Zero(), s, false, 1e-3);
  EXPECT_TRUE(held.in_contact);
  EXPECT_NEAR(held.force.z(), -1000.0 * 0.003, 0.01);
  // Beyond the snap distance: released.
  EXPECT_FALSE(r.update(Vec3(0, 0, 0.008), Vec3::Zero(), s, false, 1e-3).in_contact);
}

TEST(ZeroForceSurface, TracksTheSurfaceWithoutForce) {
  const SurfaceSnapshot s = floor_snapshot();
  SurfaceMaterial m;
  m.kind = SurfaceKind::kZeroForce;
  RendererConfig c;
  c.kind = RendererKind::kGodObject;
  HapticRenderer r(c, m, 1000.0);
  r.reset(Vec3(0, 0, 0.01));
  r.update(Vec3(0, 0, -0.004), Vec3::Zero(), s, false, 1e-3);
  const ContactState& contact = r.update(Vec3(0, 0, -0.004), Vec3::Zero(), s, false, 1e-3);
  EXPECT_TRUE(contact.in_contact);
  EXPECT_EQ(contact.force, Vec3::Zero());
  EXPECT_NEAR(contact.penetration_m, 0.004, 1e-5);  // the needle's depth
  EXPECT_NEAR(contact.proxy.z(), 0.0, 1e-5);
}

TEST(ForceEffects, SpringActivatesInsideStartAndReleasesOutsideEscape) {
  ForceEffects effects;
  SpringEffect spring;
  spring.position_m = Vec3(0, 0, 0);
  spring.start_distance_m = 0.01;
  spring.escape_distance_m = 0.02;
  effects.springs.push_back(spring);
  EXPECT_EQ(effects.evaluate(Vec3(0.015, 0, 0), Vec3::Zero()), Vec3::Zero());  // not yet caught
  EXPECT_NEAR(effects.evaluate(Vec3(0.005, 0, 0), Vec3::Zero()).x(), -100.0 * 0.005, 1e-12);
  EXPECT_NEAR(effects.evaluate(Vec3(0.015, 0, 0), Vec3::Zero()).x(), -100.0 * 0.015, 1e-12);  // held
  EXPECT_EQ(effects.evaluate(Vec3(0.025, 0, 0), Vec3::Zero()), Vec3::Zero());  // escaped
}

TEST(ForceEffects, ViscosityIsStokesDragAndConstantAdds) {
  ForceEffects effects;
  effects.viscosities.push_back(ViscosityEffect{});
  effects.constants.push_back(ConstantForceEffect{Vec3(0, 1.0, 0)});
  const Vec3 v(0.2, 0, 0);
  const Vec3 f = effects.evaluate(Vec3::Zero(), v);
  EXPECT_NEAR(f.x(), -0.5 * 6 * std::numbers::pi * 0.01 * 0.0025 * 0.2, 1e-15);
  EXPECT_NEAR(f.y(), 1.0, 1e-15);
}

TEST(HapticTick, AllocatesNothing) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  testing::ProgrammedDevice device([](double t) { return Vec3(0.03 * std::sin(5 * t), 0.0, 0.002 - 0.01 * std::min(t, 0.5)); });
  TripleBuffer<SurfaceSnapshot> surfaces(floor_snapshot());
  surfaces.write_slot() = floor_snapshot();
  surfaces.publish();
  for (RendererKind kind : {RendererKind::kPenalty, RendererKind::kGodObject, RendererKind::kRuspini}) {
    HapticLoopConfig config;
    config.renderer.kind = kind;
    config.material.kind = SurfaceKind::kFrictional;
    config.realtime_priority = false;
    config.telemetry_capacity = 1 << 12;
    HapticLoop loop(device, surfaces, config);
    loop.effects().springs.push_back(SpringEffect{});
    loop.effects().viscosities.push_back(ViscosityEffect{});
    HapticSample sample;
    for (int i = 0; i < 100; ++i) loop.tick(i * 1e-3);
    const long before = hof::testing::allocation_count();
    for (int i = 100; i < 2000; ++i) {
      loop.tick(i * 1e-3);
      loop.telemetry().pop(sample);
    }
    EXPECT_EQ(hof::testing::allocation_count() - before, 0) << "renderer " << static_cast<int>(kind);
  }
}

}  // namespace
}  // namespace hof::haptics
