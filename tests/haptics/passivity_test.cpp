// Colgate & Schenkel's passivity bound for a sampled virtual wall: with wall stiffness K,
// sampling period T and device damping b, the wall is passive when b > K·T/2 (Colgate &
// Schenkel, J. Robotic Systems 14(1), 1997). A virtual hand (mass on a soft arm, exact
// zero-order-hold dynamics) presses on a god-object wall rendered by the haptic loop in
// virtual time; energy decays above the bound and grows below it.

#include <gtest/gtest.h>

#include "haptics_test_support.h"
#include "hof/haptics/device_backends/virtual_hand_device.h"
#include "hof/haptics/haptic_loop.h"

namespace hof::haptics {
namespace {

struct EnergyTrend {
  double early{0.0};  // mean mechanical energy over the first second, J
  double late{0.0};   // over the last second
};

EnergyTrend press_on_wall(double wall_stiffness, double device_damping) {
  constexpr double kRate = 1000.0;
  const Vec3 target(0.0, 0.0, -0.005);  // 5 mm inside the wall: the arm keeps pressing
  VirtualHandParams hand;
  hand.mass_kg = 0.1;
  hand.stiffness_n_per_m = 50.0;  // arm ≪ wall
  hand.damping_n_s_per_m = 0.0;
  hand.device_damping_n_s_per_m = device_damping;
  hand.substep_s = 1.0 / kRate;
  hand.integrator = HandIntegrator::kExactZeroOrderHold;
  DeviceSpec spec;
  spec.max_force_n = 1000.0;  // no clamp in the way of the dynamics
  spec.max_force_rate_n_per_s = 1e9;
  spec.max_stiffness_n_per_m = wall_stiffness;
  VirtualHandDevice device(ScriptedMotion::stationary(target), hand, spec);
  device.reset(0.0, Vec3(0, 0, 0.002), Vec3(0, 0, -0.05));  // arriving at 5 cm/s

  SurfaceSnapshot wall = make_snapshot(testing::box_surface(Vec3(-0.2, -0.2, -0.1), Vec3(0.2, 0.2, 0.0)));
  wall.is_static = true;
  TripleBuffer<SurfaceSnapshot> surfaces(wall);
  surfaces.write_slot() = wall;
  surfaces.publish();
  HapticLoopConfig config;
  config.rate_hz = kRate;
  config.renderer.kind = RendererKind::kGodObject;
  config.material.stiffness = 1.0;  // relative: = spec.max_stiffness = K
  config.material.damping_n_s_per_m = 0.0;
  config.safety.fade_in_s = 0.0;
  config.realtime_priority = false;
  HapticLoop loop(device, surfaces, config);

  EnergyTrend trend;
  const int ticks = 6000;
  for (int i = 0; i < ticks; ++i) {
    loop.tick(i / kRate);
    const Vec3 x = device.position();
    const double penetration = std::max(0.0, -x.z());
    const double energy = device.kinetic_energy() + 0.5 * hand.stiffness_n_per_m * (x - target).squaredNorm() +
                          0.5 * wall_stiffness * penetration * penetration;
    if (i < 1000) trend.early += energy / 1000.0;
    if (i >= ticks - 1000) trend.late += energy / 1000.0;
  }
  return trend;
}

TEST(Passivity, WallIsStableAboveColgatesBound) {
  const double k = 2000.0, t = 1e-3;  // K·T/2 = 1 N·s/m
  const EnergyTrend stable = press_on_wall(k, 2.0 * k * t / 2.0);
  EXPECT_LT(stable.late, stable.early) << "energy must not grow with b = 2·K·T/2";
}

TEST(Passivity, WallGainsEnergyBelowColgatesBound) {
  const double k = 2000.0, t = 1e-3;
  const EnergyTrend unstable = press_on_wall(k, 0.2 * k * t / 2.0);
  EXPECT_GT(unstable.late, 2.0 * unstable.early) << "with b = 0.2·K·T/2 the sampled wall pumps energy in";
}

}  // namespace
}  // namespace hof::haptics
