// Tests of the mouse stylus (device_backends/mouse_device.cpp): it follows its target
// smoothly, jumps when placed, ignores a non-finite target.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/haptics/device_config.h"

namespace hof::haptics {
namespace {

TEST(MouseDevice, FollowsItsTargetSmoothlyAndJumpsWhenPlaced) {
  auto opened = open_device(MouseConfig{});
  ASSERT_TRUE(opened) << opened.error().to_string();
  auto* mouse = dynamic_cast<MouseDevice*>(opened->get());
  ASSERT_NE(mouse, nullptr);
  EXPECT_EQ((*opened)->backend(), "mouse");
  mouse->place(Vec3(0.0, 0.0, 0.05));
  DeviceReading r = mouse->read(0.0);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.position_m, Vec3(0.0, 0.0, 0.05));
  // A target 2 cm away: first-order approach with tau = 20 ms (1 - e^-1 of the way after 20 ms),
  // never overshooting, velocity toward it.
  mouse->set_target(Vec3(0.0, 0.0, 0.03), 1);
  double t = 0.0;
  for (int i = 0; i < 20; ++i) r = mouse->read(t += 0.001);
  EXPECT_NEAR(r.position_m.z(), 0.05 - 0.02 * (1.0 - std::exp(-1.0)), 1e-9);
  EXPECT_LT(r.velocity_m_per_s.z(), 0.0);
  EXPECT_EQ(r.buttons, 1u);
  for (int i = 0; i < 500; ++i) r = mouse->read(t += 0.001);
  EXPECT_NEAR(r.position_m.z(), 0.03, 1e-9);
  EXPECT_GE(r.position_m.z(), 0.03);
  mouse->place(Vec3(0.1, 0.0, 0.0));
  r = mouse->read(t += 0.001);
  EXPECT_EQ(r.position_m, Vec3(0.1, 0.0, 0.0));
  // Placed, then given a target before any reading (the window placing a new mouse stylus and
  // moving it in the same frame): the first reading is where it was placed.
  MouseDevice fresh;
  fresh.place(Vec3(0.0, 0.0, 0.05));
  fresh.set_target(Vec3(0.0, 0.0, -0.05));
  EXPECT_EQ(fresh.read(0.0).position_m, Vec3(0.0, 0.0, 0.05));
  EXPECT_LT(fresh.read(0.001).position_m.z(), 0.05);
  // A non-finite target is ignored (never a NaN position).
  mouse->set_target(Vec3(std::nan(""), 0.0, 0.0));
  r = mouse->read(t += 0.001);
  EXPECT_TRUE(r.position_m.allFinite());
}

}  // namespace
}  // namespace hof::haptics
