// Real haptic devices through their vendors' SDKs, loaded at run time — tested through
// stand-in libraries (tests/haptics/standins/) that export the SDKs' C functions and
// simulate a device: the real dlopen path, the units and frames, the force limits, the
// OpenHaptics scheduler driving the tick, faults, and no allocation in the tick.

#include <dlfcn.h>
#include <gtest/gtest.h>

#include "support/allocation_counter.h"

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "hof/coupling/session.h"
#include "hof/haptics/device.h"
#include "hof/haptics/device_backends/dhd_device.h"
#include "hof/haptics/device_backends/openhaptics_device.h"
#include "hof/haptics/device_config.h"
#include "hof/haptics/haptic_loop.h"
#include "support/box_surface.h"

namespace hof::haptics {
namespace {

// The stand-in's own functions, from the same file the device loaded (one instance).
class Standin {
 public:
  explicit Standin(const char* path) : handle_(::dlopen(path, RTLD_NOW | RTLD_LOCAL)) {}
  ~Standin() {
    if (handle_) ::dlclose(handle_);
  }
  Standin(const Standin&) = delete;
  Standin& operator=(const Standin&) = delete;
  template <class F>
  F* get(const char* name) const {
    EXPECT_NE(handle_, nullptr) << ::dlerror();
    auto* f = reinterpret_cast<F*>(::dlsym(handle_, name));
    EXPECT_NE(f, nullptr) << name;
    return f;
  }

 private:
  void* handle_;
};

struct Dhd {
  Standin lib{HOF_DHD_STANDIN};
  void (*reset)(int, int, double) = lib.get<void(int, int, double)>("standin_dhd_reset");
  void (*hand)(double, double, double, double, double,
               double) = lib.get<void(double, double, double, double, double, double)>("standin_dhd_set_hand");
  void (*fault)(int, long, int) = lib.get<void(int, long, int)>("standin_dhd_set_fault");
  long (*forces)(double*, int*, double*) = lib.get<long(double*, int*, double*)>("standin_dhd_forces");
  long (*reads)() = lib.get<long()>("standin_dhd_reads");
  int (*open)() = lib.get<int()>("standin_dhd_open");
};

// The stand-ins' configurations (spec strings are scene/'s: `dhd,library=...`).
const DhdConfig kDhd{0, HOF_DHD_STANDIN, std::nullopt};
const OpenHapticsConfig kHd{"", HOF_HD_STANDIN, std::nullopt};

TEST(SdkDevices, AMissingSdkIsAClearErrorNamingTheFileAndWhereItWasLookedFor) {
  for (const DeviceConfig& config : {DeviceConfig(DhdConfig{0, "/nowhere/libdhd.so", std::nullopt}),
                                     DeviceConfig(OpenHapticsConfig{"", "/nowhere/libHD.so", std::nullopt})}) {
    const bool dhd = std::holds_alternative<DhdConfig>(config);
    auto device = open_device(config);
    ASSERT_FALSE(device);
    const std::string m = device.error().to_string();
    EXPECT_NE(m.find("/nowhere/lib"), std::string::npos) << m;
    EXPECT_NE(m.find("LD_LIBRARY_PATH"), std::string::npos) << m;
    EXPECT_NE(m.find("docs/devices.md"), std::string::npos) << m;
    EXPECT_NE(m.find(dhd ? "Force Dimension SDK" : "OpenHaptics"), std::string::npos) << m;
  }
  // By default the loader's own search: this machine has neither SDK.
  ::unsetenv("HOF_DHD_LIBRARY");
  auto device = open_device(DhdConfig{});
  ASSERT_FALSE(device);
  EXPECT_NE(device.error().message.find("libdhd.so"), std::string::npos) << device.error().message;
}

TEST(SdkDevices, AnSdkWithoutAFunctionHoFNeedsIsAClearErrorNamingIt) {
  auto device = open_device(DhdConfig{0, HOF_DHD_STANDIN_WITHOUT_SET_FORCE, std::nullopt});
  ASSERT_FALSE(device);
  const std::string m = device.error().to_string();
  EXPECT_NE(m.find("'dhdSetForce'"), std::string::npos) << m;
  EXPECT_NE(m.find(HOF_DHD_STANDIN_WITHOUT_SET_FORCE), std::string::npos) << m;
}

TEST(SdkDevices, NoDeviceOrAnIndexPastTheDevicesIsAClearError) {
  Dhd dhd;
  dhd.reset(0, 33, -1.0);
  auto none = open_device(kDhd);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("no device found by the Force Dimension SDK"), std::string::npos)
      << none.error().message;
  dhd.reset(1, 33, -1.0);
  auto past = open_device(DhdConfig{2, HOF_DHD_STANDIN, std::nullopt});
  ASSERT_FALSE(past);
  EXPECT_NE(past.error().message.find("found 1 device"), std::string::npos) << past.error().message;
  EXPECT_EQ(dhd.open(), 0);
}

TEST(SdkDevices, ForceDimensionPositionsArriveInMetresInHoFsFrameWithTheSdksLimits) {
  Dhd dhd;
  dhd.reset(1, 60, -1.0);  // a Falcon, no limit reported by the SDK: the table's
  {
    auto device = open_device(kDhd);
    ASSERT_TRUE(device) << device.error().to_string();
    EXPECT_EQ((*device)->spec().max_force_n, 8.0);
    EXPECT_EQ((*device)->spec().workspace_radius_m, 0.04);
  }
  dhd.reset(1, 33, 5.0);  // an omega.3 whose SDK says 5 N
  auto device = open_device(kDhd);
  ASSERT_TRUE(device) << device.error().to_string();
  Device& d = **device;
  EXPECT_EQ(d.spec().model, "omega.3 (stand-in)");
  EXPECT_EQ(d.spec().max_force_n, 5.0);
  EXPECT_EQ(dhd.open(), 1);
  // SDK frame: x toward the user, y right, z up — HoF's: x right, y up, z toward the user.
  dhd.hand(0.01, 0.02, 0.03, 0.1, 0.2, 0.3);
  const DeviceReading r = d.read(0.0);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.position_m, Vec3(0.02, 0.03, 0.01));
  EXPECT_EQ(r.velocity_m_per_s, Vec3(0.2, 0.3, 0.1));
  EXPECT_EQ(r.buttons, 1u);
  d.write_force(Vec3(1.0, 2.0, 3.0), Vec3::Zero());
  double max = 0.0, last[3]{};
  int non_finite = 0;
  EXPECT_EQ(dhd.forces(&max, &non_finite, last), 1);
  EXPECT_EQ(last[0], 3.0);  // toward the user
  EXPECT_EQ(last[1], 1.0);  // right
  EXPECT_EQ(last[2], 2.0);  // up
  d.close();
  EXPECT_EQ(dhd.open(), 0);
}

// A 4 cm box (top at y = 0) in the world; the device's frame is the world's.
std::vector<coupling::SessionBody> box_world() {
  std::vector<coupling::SessionBody> bodies(1);
  bodies[0].name = "box";
  bodies[0].surface = hof::testing::box_surface(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  return bodies;
}

coupling::SessionConfig press_config() {
  coupling::SessionConfig config;
  config.haptics.renderer.kind = RendererKind::kGodObject;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  config.pin_threads = false;
  return config;
}

TEST(SdkDevices, ForcesReachAForceDimensionDeviceClampedToItsLimitAndInItsFrame) {
  Dhd dhd;
  dhd.reset(1, 33, 5.0);
  auto device = open_device(kDhd);
  ASSERT_TRUE(device) << device.error().to_string();
  auto session = coupling::Session::make(box_world(), std::move(*device), press_config());
  ASSERT_TRUE(session) << session.error().to_string();
  dhd.hand(0.0, 0.0, 0.01, 0, 0, 0);  // 1 cm above the box
  (*session)->run_virtual(0.1, {});
  dhd.hand(0.0, 0.0, -0.02, 0, 0, 0);  // 2 cm into it: 1,500 N/m asks 30 N
  (*session)->run_virtual(0.5, {});
  double max = 0.0, last[3]{};
  int non_finite = 0;
  EXPECT_GT(dhd.forces(&max, &non_finite, last), 500);
  EXPECT_EQ(non_finite, 0);
  EXPECT_LE(max, 5.0 + 1e-12);
  EXPECT_GT(max, 4.99);
  EXPECT_NEAR(last[2], 5.0, 1e-9);  // up, in the SDK's frame
  EXPECT_NEAR(last[0], 0.0, 1e-9);
  EXPECT_NEAR(last[1], 0.0, 1e-9);
}

// The stand-in fails (kind 1: every call errs, as an unplugged device; 2: NaN positions)
// while the hand presses: the force fades to zero, the run ends early and says why.
void expect_the_run_ends_on_a_fault(int kind, const std::string& why) {
  Dhd dhd;
  dhd.reset(1, 33, -1.0);
  dhd.hand(0.0, 0.0, -0.003, 0, 0, 0);
  auto device = open_device(kDhd);
  ASSERT_TRUE(device) << device.error().to_string();
  auto session = coupling::Session::make(box_world(), std::move(*device), press_config());
  ASSERT_TRUE(session) << session.error().to_string();
  (*session)->run_virtual(0.2, {});
  dhd.fault(kind, dhd.reads() + 100, 0);
  HapticSample last;
  int samples = 0;
  const coupling::SessionReport report = (*session)->run_virtual(5.0, [&](const HapticSample& s) {
    last = s;
    ++samples;
  });
  EXPECT_NE(report.device_failure.find(why), std::string::npos) << report.device_failure;
  EXPECT_LT(report.simulated_s, 1.0);  // ended early
  EXPECT_GT(samples, 100);
  EXPECT_EQ(last.force, Vec3::Zero());  // faded out
  double max = 0.0, sent[3]{};
  int non_finite = 0;
  dhd.forces(&max, &non_finite, sent);
  EXPECT_EQ(non_finite, 0);
  EXPECT_LE(max, 12.0);
  EXPECT_EQ((*session)->haptic_loop().device().health(), DeviceHealth::kFailed);
}

TEST(SdkDevices, AForceDimensionDeviceUnpluggedMidRunFadesTheForceAndEndsTheRun) {
  expect_the_run_ends_on_a_fault(1, "communication error (stand-in: unplugged)");
}

TEST(SdkDevices, AForceDimensionDeviceGivingNaNFadesTheForceAndEndsTheRun) {
  expect_the_run_ends_on_a_fault(2, "not a number");
}

// A device whose SDK call stalls (200 ms in one read, on the haptic thread): the loop goes
// on after it, the stall is in the period statistics, and the force never passes the limit.
TEST(SdkDevices, AForceDimensionDeviceThatStallsIsWaitedForAndTheRunGoesOn) {
  Dhd dhd;
  dhd.reset(1, 33, 5.0);
  dhd.hand(0.0, 0.0, 0.01, 0, 0, 0);
  auto device = open_device(kDhd);
  ASSERT_TRUE(device) << device.error().to_string();
  auto session = coupling::Session::make(box_world(), std::move(*device), press_config());
  ASSERT_TRUE(session) << session.error().to_string();
  dhd.fault(3, dhd.reads() + 300, 200);
  (*session)->start_realtime();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  dhd.hand(0.0, 0.0, -0.02, 0, 0, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  const coupling::SessionReport report = (*session)->stop_realtime();
  EXPECT_GE(report.haptic_periods.max_s(), 0.2);
  EXPECT_GE(report.haptic_periods.overruns(), 1u);
  EXPECT_TRUE(report.device_failure.empty());
  double max = 0.0, last[3]{};
  int non_finite = 0;
  EXPECT_GT(dhd.forces(&max, &non_finite, last), 100);  // ticks went on after the stall
  EXPECT_EQ(non_finite, 0);
  EXPECT_LE(max, 5.0 + 1e-12);
}

TEST(SdkDevices, TheTickThroughAnSdkDeviceAllocatesNothing) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  Dhd dhd;
  dhd.reset(1, 33, -1.0);
  dhd.hand(0.0, 0.0, -0.002, 0, 0, 0);
  auto device = open_device(kDhd);
  ASSERT_TRUE(device) << device.error().to_string();
  auto session = coupling::Session::make(box_world(), std::move(*device), press_config());
  ASSERT_TRUE(session) << session.error().to_string();
  (*session)->run_virtual(0.2, {});
  // The haptic loop's own ticks, on this thread (the session's step allocates nothing either,
  // but is not what this checks).
  HapticLoop& loop = const_cast<HapticLoop&>((*session)->haptic_loop());
  HapticSample sample;
  const long before = hof::testing::thread_allocation_count();
  for (int i = 0; i < 1000; ++i) {
    loop.tick(10.0 + i * 1e-3);
    while (loop.telemetry().pop(sample)) {
    }
  }
  EXPECT_EQ(hof::testing::thread_allocation_count() - before, 0);
  EXPECT_GT(dhd.reads(), 1000);
}

struct Hd {
  Standin lib{HOF_HD_STANDIN};
  void (*hand_mm)(double, double, double) = lib.get<void(double, double, double)>("standin_hd_set_hand_mm");
  void (*calibration)(int) = lib.get<void(int)>("standin_hd_set_calibration");
  long (*frames)() = lib.get<long()>("standin_hd_frames");
  long (*outside)() = lib.get<long()>("standin_hd_forces_outside_frame");
  double (*max_force)() = lib.get<double()>("standin_hd_max_force");
  void (*last_force)(double*) = lib.get<void(double*)>("standin_hd_last_force");
};

TEST(SdkDevices, OpenHapticsLimitsAndCalibrationComeFromTheDevice) {
  Hd hd;
  hd.calibration(0x5002);  // needs manual input
  auto device = open_device(kHd);
  ASSERT_TRUE(device) << device.error().to_string();
  const DeviceSpec& spec = (*device)->spec();
  EXPECT_EQ(spec.model, "Touch (stand-in)");
  EXPECT_EQ(spec.max_force_n, 3.3);
  EXPECT_NEAR(spec.max_stiffness_n_per_m, 1260.0, 1e-9);  // N/mm → N/m
  EXPECT_NEAR(spec.workspace_radius_m, 0.035, 1e-12);     // the usable box's smallest half-extent
  EXPECT_NE(openhaptics_calibration(**device).find("manual input"), std::string::npos);
  auto unknown = open_device(OpenHapticsConfig{"Phantom Premium 9", HOF_HD_STANDIN, std::nullopt});
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("Device fault (stand-in)"), std::string::npos) << unknown.error().message;
}

TEST(SdkDevices, OpenHapticsServoFramesDriveOneTickEachWithMillimetresConvertedOnce) {
  Hd hd;
  hd.calibration(0x5000);
  hd.hand_mm(5.0, 10.0, 3.0);  // above the box
  auto device = open_device(kHd);
  ASSERT_TRUE(device) << device.error().to_string();
  auto session = coupling::Session::make(box_world(), std::move(*device), press_config());
  ASSERT_TRUE(session) << session.error().to_string();
  const long frames_before = hd.frames();
  Vec3 last_device = Vec3::Zero();
  const auto on_sample = [&](const HapticSample& s) { last_device = s.device; };
  (*session)->start_realtime();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  hd.hand_mm(5.0, -10.0, 3.0);  // 10 mm into it
  for (int i = 0; i < 150; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    (*session)->poll(on_sample);
  }
  const coupling::SessionReport report = (*session)->stop_realtime(on_sample);
  const long frames = hd.frames() - frames_before;
  EXPECT_EQ((*session)->haptic_loop().scheduling(), HapticLoop::Scheduling::device_servo);
  EXPECT_GT(frames, 100);
  EXPECT_EQ(report.haptic_ticks, frames);  // one tick per servo frame, every frame
  EXPECT_EQ(hd.outside(), 0);              // forces only inside a frame
  EXPECT_TRUE(last_device.isApprox(Vec3(0.005, -0.010, 0.003), 1e-12)) << last_device.transpose();
  // 10 mm deep asks 15 N: clamped to the nominal 3.3 N, then held to the continuous 0.88 N
  // as the force's mean over the last second rises past it.
  EXPECT_LE(hd.max_force(), 3.3 + 1e-12);
  EXPECT_GT(hd.max_force(), 0.88);
  double last[3]{};
  hd.last_force(last);
  if (frames > 1200) {
    EXPECT_LT(std::hypot(last[0], last[1], last[2]), 0.88 * 1.05);
  }
}

}  // namespace
}  // namespace hof::haptics
