// (GCC cannot see that the replaced operator new uses malloc.)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

// Tests of open_device(const DeviceConfig&) (device_backends/open_device.cpp): every backend's
// read() and write_force() never allocate, and errors are the backend's own.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "hof/haptics/device_config.h"
#include "support/allocation_counter.h"
#include "support/temp_dir.h"

namespace hof::haptics {
namespace {

using hof::testing::TempDir;
namespace fs = std::filesystem;

TEST(DeviceBackends, ReadAndWriteForceNeverAllocate) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  TempDir dir;
  const auto path = dir.write("n.csv", "t,x,y,z,qw,qx,qy,qz,button\n0,0,0,0,1,0,0,0,0\n1,0.01,0,0,0,0,0,1,1\n");
  std::vector<std::unique_ptr<Device>> devices;
  MotionConfig slide;
  slide.kind = MotionKind::kPressAndSlide;
  MotionConfig circle;
  circle.kind = MotionKind::kCircle;
  circle.repeat = 0;  // forever
  MotionConfig poke;
  poke.repeat = 0;
  VirtualHandParams exact;
  exact.integrator = HandIntegrator::kExactZeroOrderHold;
  for (const DeviceConfig& config :
       {DeviceConfig{ReplayConfig{path, true, {}}}, DeviceConfig{ScriptedConfig{slide, {}}},
        DeviceConfig{VirtualHandConfig{circle, {}, {}}}, DeviceConfig{VirtualHandConfig{poke, exact, {}}}}) {
    auto d = open_device(config);
    ASSERT_TRUE(d) << d.error().to_string();
    devices.push_back(std::move(*d));
  }
  double sum = 0.0;
  const long before = hof::testing::thread_allocation_count();
  for (int i = 0; i < 3000; ++i) {
    for (auto& d : devices) {
      const DeviceReading r = d->read(i * 1e-3);
      d->write_force(Vec3(0.1, 0.0, -0.1), Vec3::Zero());
      sum += r.position_m.x() + static_cast<double>(d->health() == DeviceHealth::kOk);
    }
  }
  EXPECT_EQ(hof::testing::thread_allocation_count() - before, 0);
  EXPECT_TRUE(std::isfinite(sum));
}

// The typed open reports the backend's own error; the spec string, where there was one, is
// named by scene::open_device (tests/scene/device_config_test.cpp).
TEST(OpenDevice, ReportsTheBackendsOwnErrors) {
  MotionConfig slow;
  slow.speed_m_per_s = -1.0;
  auto scripted = open_device(ScriptedConfig{slow, {}});
  ASSERT_FALSE(scripted);
  EXPECT_NE(scripted.error().message.find("speed must be > 0"), std::string::npos) << scripted.error().message;
  EXPECT_EQ(scripted.error().message.find("device spec"), std::string::npos) << scripted.error().message;

  VirtualHandParams weightless;
  weightless.mass_kg = -1.0;
  auto hand = open_device(VirtualHandConfig{MotionConfig{}, weightless, {}});
  ASSERT_FALSE(hand);
  EXPECT_NE(hand.error().message.find("mass must be > 0"), std::string::npos) << hand.error().message;

  auto opened = open_device(ScriptedConfig{MotionConfig{}, DeviceSpec{}});
  ASSERT_TRUE(opened) << opened.error().to_string();
  EXPECT_EQ((*opened)->backend(), "scripted");
}

}  // namespace
}  // namespace hof::haptics
