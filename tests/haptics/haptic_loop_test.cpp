// The haptic loop in virtual time (deterministic) and in real time (only what holds under any
// load: no deadlock, no torn snapshot, clean shutdown), and the safety rules.

#include "hof/haptics/haptic_loop.h"

#include <gtest/gtest.h>

#include <atomic>
#include <limits>
#include <thread>

#include "haptics_test_support.h"
#include "support/allocation_counter.h"

namespace hof::haptics {
namespace {

using testing::box_surface;
using testing::floor_snapshot;
using testing::ProgrammedDevice;

DeviceSpec omni() {
  DeviceSpec spec;  // PHANTOM Omni figures (CHAI3D): 3.3 N, 700 N/m
  spec.model = "omni";
  spec.max_force_n = 3.3;
  spec.max_stiffness_n_per_m = 700.0;
  spec.max_force_rate_n_per_s = 1e5;
  return spec;
}

HapticLoopConfig loop_config() {
  HapticLoopConfig c;
  c.renderer.kind = RendererKind::kGodObject;
  c.material.stiffness = 1.0;
  c.safety.fade_in_s = 0.0;
  c.realtime_priority = false;
  return c;
}

// Top face of a box at z = 0.
SurfaceSnapshot static_floor() {
  SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.2, -0.2, -0.1), Vec3(0.2, 0.2, 0.0)));
  s.is_static = true;
  return s;
}

// Above the floor for 20 ms, then pressed `depth` into it (a proxy starts where the device is).
Vec3 press(double t, double depth) { return t < 0.02 ? Vec3(0, 0, 0.01) : Vec3(0, 0, -depth); }

double max_force(const ProgrammedDevice& d) {
  double m = 0.0;
  for (const Vec3& f : d.forces) m = std::max(m, f.norm());
  return m;
}

TEST(Safety, TheDeviceNeverReceivesMoreThanItsLimit) {
  // Pressed 5 cm into a floor rendered at 10× the device's stiffness: 350 N requested.
  ProgrammedDevice device([](double t) { return Vec3(0, 0, 0.01 - 0.06 * std::min(1.0, t)); }, omni());
  TripleBuffer<SurfaceSnapshot> surfaces(static_floor());
  surfaces.write_slot() = static_floor();
  surfaces.publish();
  HapticLoopConfig c = loop_config();
  c.material.stiffness = 10.0;
  HapticLoop loop(device, surfaces, c);
  for (int i = 0; i < 2000; ++i) loop.tick(i * 1e-3);
  EXPECT_LE(max_force(device), 3.3);
  EXPECT_GT(max_force(device), 3.2);  // it does push, at the limit
  EXPECT_GT(loop.safety_counters().clamped, 0u);
}

TEST(Safety, NonFiniteDevicePositionsGiveZeroForce) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ProgrammedDevice device([&](double t) { return (t > 0.5 && t < 0.6) ? Vec3(nan, 0, 0) : press(t, 0.002); }, omni());
  TripleBuffer<SurfaceSnapshot> surfaces(static_floor());
  surfaces.write_slot() = static_floor();
  surfaces.publish();
  HapticLoop loop(device, surfaces, loop_config());
  for (int i = 0; i < 1000; ++i) {
    loop.tick(i * 1e-3);
    ASSERT_TRUE(device.last_force.allFinite()) << "tick " << i;
    if (i > 510 && i < 600) {
      EXPECT_EQ(device.last_force, Vec3::Zero()) << "tick " << i;
    }
    EXPECT_LE(device.last_force.norm(), 3.3);
  }
  EXPECT_GT(loop.safety_counters().non_finite, 0u);
  EXPECT_GT(device.last_force.z(), 0.5);  // recovers afterwards
}

TEST(Safety, StalledSnapshotFadesTheForceOut) {
  ProgrammedDevice device([](double t) { return press(t, 0.002); }, omni());
  SurfaceSnapshot dynamic = static_floor();
  dynamic.is_static = false;
  TripleBuffer<SurfaceSnapshot> surfaces(dynamic);
  surfaces.write_slot() = dynamic;  // published once at t = 0, then the simulation stalls
  surfaces.publish();
  HapticLoopConfig c = loop_config();
  c.safety.max_snapshot_age_s = 0.1;
  c.safety.fade_out_s = 0.05;
  HapticLoop loop(device, surfaces, c);
  for (int i = 0; i < 300; ++i) loop.tick(i * 1e-3);
  EXPECT_GT(device.forces[50].z(), 1.0);  // pushing while fresh
  EXPECT_EQ(device.last_force, Vec3::Zero());
  EXPECT_GT(loop.safety_counters().watchdog, 0u);
  // Fresh geometry brings the force back.
  for (int i = 300; i < 600; ++i) {
    SurfaceSnapshot& slot = surfaces.write_slot();
    slot = dynamic;
    slot.time_s = i * 1e-3;
    surfaces.publish();
    loop.tick(i * 1e-3);
  }
  EXPECT_GT(device.last_force.z(), 1.0);
}

TEST(Safety, ForceFadesInAtStartAndRespectsTheSlewLimit) {
  DeviceSpec spec = omni();
  spec.max_force_rate_n_per_s = 100.0;  // 0.1 N per 1 ms tick
  ProgrammedDevice device([](double t) { return press(t, 0.004); }, spec);
  TripleBuffer<SurfaceSnapshot> surfaces(static_floor());
  surfaces.write_slot() = static_floor();
  surfaces.publish();
  HapticLoopConfig c = loop_config();
  c.safety.fade_in_s = 0.2;
  HapticLoop loop(device, surfaces, c);
  for (int i = 0; i < 400; ++i) loop.tick(i * 1e-3);
  EXPECT_LT(device.forces[25].norm(), 0.1 * 6 + 1e-12);
  for (std::size_t i = 1; i < device.forces.size(); ++i) {
    EXPECT_LE((device.forces[i] - device.forces[i - 1]).norm(), 0.1 + 1e-9);
  }
  EXPECT_NEAR(device.last_force.z(), 700.0 * 0.004, 1e-3);  // + the proxy's 1 µm clearance
}

TEST(Safety, RepeatedOverrunsFadeTheForceOut) {
  SafetyConfig config;
  config.fade_in_s = 0.0;
  config.fade_out_s = 0.01;
  config.max_consecutive_overruns = 5;
  SafetyFilter filter(omni(), config);
  EXPECT_NEAR(filter.filter(Vec3(0, 0, 2), SafetyFilter::Reading::kValid, 0.0, false, 1e-3).z(), 2.0, 1e-12);
  Vec3 f = Vec3::Zero();
  for (int i = 0; i < 4; ++i) f = filter.filter(Vec3(0, 0, 2), SafetyFilter::Reading::kValid, 0.0, true, 1e-3);
  EXPECT_NEAR(f.z(), 2.0, 1e-12);  // a few late ticks are tolerated
  for (int i = 0; i < 20; ++i) f = filter.filter(Vec3(0, 0, 2), SafetyFilter::Reading::kValid, 0.0, true, 1e-3);
  EXPECT_EQ(f, Vec3::Zero());  // a loop that keeps overrunning fades to zero
  EXPECT_GT(filter.counters().watchdog, 0u);
  for (int i = 0; i < 20; ++i) f = filter.filter(Vec3(0, 0, 2), SafetyFilter::Reading::kValid, 0.0, false, 1e-3);
  EXPECT_NEAR(f.z(), 2.0, 1e-12);  // and recovers once it keeps its rate
}

TEST(Safety, AUserForceLimitBelowTheDevicesHoldsAndOneAboveDoesNot) {
  SafetyConfig config;
  config.fade_in_s = 0.0;
  config.max_force_n = 1.5;  // below the Omni's 3.3 N
  SafetyFilter filter(omni(), config);
  EXPECT_DOUBLE_EQ(filter.force_limit_n(), 1.5);
  Vec3 f = Vec3::Zero();
  for (int i = 0; i < 50; ++i) f = filter.filter(Vec3(0, 0, 3), SafetyFilter::Reading::kValid, 0.0, false, 1e-3);
  EXPECT_LE(f.norm(), 1.5);
  EXPECT_NEAR(f.norm(), 1.5, 1e-9);
  filter.set_max_force(10.0);  // above the device: the device's limit
  EXPECT_DOUBLE_EQ(filter.force_limit_n(), omni().max_force_n);
  for (int i = 0; i < 50; ++i) f = filter.filter(Vec3(0, 0, 5), SafetyFilter::Reading::kValid, 0.0, false, 1e-3);
  EXPECT_NEAR(f.norm(), omni().max_force_n, 1e-9);
  filter.set_max_force(0.0);  // 0: the device's
  EXPECT_DOUBLE_EQ(filter.force_limit_n(), omni().max_force_n);
}

TEST(Safety, MissingReadingsAreCountedApartFromNonFiniteOnes) {
  SafetyConfig config;
  config.fade_in_s = 0.0;
  config.fade_out_s = 0.0;
  SafetyFilter filter(omni(), config);
  EXPECT_EQ(filter.filter(Vec3(0, 0, 2), SafetyFilter::Reading::kMissing, 0.0, false, 1e-3), Vec3::Zero());
  EXPECT_EQ(filter.counters().no_reading, 1u);
  EXPECT_EQ(filter.counters().non_finite, 0u);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(filter.filter(Vec3(0, 0, 2), SafetyFilter::Reading::kNonFinite, 0.0, false, 1e-3), Vec3::Zero());
  EXPECT_EQ(filter.filter(Vec3(nan, 0, 2), SafetyFilter::Reading::kValid, 0.0, false, 1e-3), Vec3::Zero());
  EXPECT_EQ(filter.counters().non_finite, 2u);
  EXPECT_EQ(filter.counters().no_reading, 1u);
}

TEST(VirtualTime, TwoRunsGiveIdenticalSamples) {
  auto run = [] {
    ProgrammedDevice device([](double t) { return Vec3(0.02 * std::sin(3 * t), 0.01 * t, 0.005 - 0.01 * t); }, omni());
    TripleBuffer<SurfaceSnapshot> surfaces(static_floor());
    surfaces.write_slot() = static_floor();
    surfaces.publish();
    HapticLoopConfig c = loop_config();
    c.renderer.kind = RendererKind::kRuspini;
    HapticLoop loop(device, surfaces, c);
    std::vector<Vec3> out;
    for (int i = 0; i < 1500; ++i) {
      loop.tick(i * 1e-3);
      out.push_back(device.last_force);
    }
    return out;
  };
  EXPECT_EQ(run(), run());
}

TEST(RealTime, RunsWithAConcurrentProducerAndStopsCleanly) {
  ProgrammedDevice device([](double t) { return Vec3(0.01 * std::sin(t), 0, -0.001); }, omni());
  SurfaceSnapshot dynamic = static_floor();
  TripleBuffer<SurfaceSnapshot> surfaces(dynamic);
  HapticLoop loop(device, surfaces, loop_config());
  std::atomic<bool> producing{true};
  std::thread producer([&] {
    // The "simulation": republishes the floor, moved a little, as fast as it can for a while.
    std::vector<Vec3> moved = dynamic.vertices;
    for (int k = 0; producing.load(); ++k) {
      for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = dynamic.vertices[i] + Vec3(0, 0, 1e-4 * (k % 3));
      SurfaceSnapshot& slot = surfaces.write_slot();
      update_snapshot(slot, moved, {}, 0.0);
      slot.is_static = true;
      surfaces.publish();
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  loop.start();
  // Drain telemetry concurrently, as the logger would.
  std::uint64_t logged = 0;
  HapticSample sample;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  while (std::chrono::steady_clock::now() < deadline) {
    while (loop.telemetry().pop(sample)) ++logged;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  loop.stop();
  producing.store(false);
  producer.join();
  while (loop.telemetry().pop(sample)) ++logged;
  EXPECT_FALSE(loop.running());
  EXPECT_GT(loop.ticks(), 10u);
  EXPECT_EQ(logged + loop.telemetry().dropped(), loop.ticks());  // none lost without a count
  EXPECT_EQ(device.last_force, Vec3::Zero());                    // stop() leaves zero force
  EXPECT_GT(loop.period_stats().count(), 0u);
}

TEST(HapticTick, AllocatesNothing) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  testing::ProgrammedDevice device(
      [](double t) { return Vec3(0.03 * std::sin(5 * t), 0.0, 0.002 - 0.01 * std::min(t, 0.5)); });
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
