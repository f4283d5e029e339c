// Tests of the virtual hand (device_backends/virtual_hand_device.cpp): its statics, following
// a target, both integrators and Colgate's passivity bound.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/haptics/device_backends/virtual_hand_device.h"

namespace hof::haptics {
namespace {

ScriptedMotion make_motion(const MotionConfig& config) {
  auto m = ScriptedMotion::make(config);
  EXPECT_TRUE(m) << m.error().to_string();
  return *m;
}

double hand_energy(const VirtualHandDevice& hand, const Vec3& target) {
  return hand.kinetic_energy() + 0.5 * hand.params().stiffness_n_per_m * (hand.position() - target).squaredNorm();
}

TEST(VirtualHandDevice, ConvergesToTheTargetWithZeroForce) {
  const Vec3 target(0.01, 0.02, -0.01);
  VirtualHandDevice hand(ScriptedMotion::stationary(target), VirtualHandParams{});
  hand.reset(0.0, target + Vec3(0.02, -0.01, 0.005));
  const double e0 = hand_energy(hand, target);
  double peak = e0;
  for (int i = 1; i <= 5000; ++i) {
    const DeviceReading r = hand.read(i * 1e-3);
    ASSERT_TRUE(r.valid);
    hand.write_force(Vec3::Zero(), Vec3::Zero());
    peak = std::max(peak, hand_energy(hand, target));
  }
  EXPECT_NEAR((hand.position() - target).norm(), 0.0, 1e-9);
  EXPECT_LT(hand.kinetic_energy(), 1e-15);
  EXPECT_LE(peak, e0 * 1.01);  // damped: the energy never grows (beyond integration wiggle)
}

TEST(VirtualHandDevice, FollowsAMovingTarget) {
  MotionConfig c;
  c.kind = MotionKind::kCircle;
  c.repeat = 0;
  const ScriptedMotion circle = make_motion(c);
  VirtualHandDevice hand(circle, VirtualHandParams{});
  double worst = 0.0;
  for (int i = 0; i <= 6000; ++i) {
    const double t = i * 1e-3;
    const DeviceReading r = hand.read(t);
    if (t > 2.0) worst = std::max(worst, (r.position_m - circle.position(t)).norm());
  }
  EXPECT_LT(worst, 0.1 * c.radius_m);  // tracks a 2 s circle within a few mm
}

TEST(VirtualHandDevice, ConstantForceDisplacesByForceOverStiffness) {
  const Vec3 target(0.0, 0.05, 0.0);
  VirtualHandParams params;
  params.device_damping_n_s_per_m = 1.0;
  VirtualHandDevice hand(ScriptedMotion::stationary(target), params);
  const Vec3 force(0.5, 2.0, -1.0);
  hand.read(0.0);
  for (int i = 1; i <= 10000; ++i) {
    hand.write_force(force, Vec3::Zero());
    hand.read(i * 1e-3);
  }
  EXPECT_NEAR((hand.position() - (target + force / params.stiffness_n_per_m)).norm(), 0.0, 1e-9);
}

TEST(VirtualHandDevice, OneSemiImplicitEulerSubstepPerMillisecondTick) {
  VirtualHandParams p;
  p.device_damping_n_s_per_m = 0.5;
  const Vec3 target(0, 0, 0);
  VirtualHandDevice hand(ScriptedMotion::stationary(target), p);
  hand.reset(0.0, Vec3(0.01, 0, 0));
  Vec3 x(0.01, 0, 0);
  Vec3 v = Vec3::Zero();
  const Vec3 f(0.3, -0.2, 0.1);
  for (int i = 1; i <= 100; ++i) {
    hand.write_force(f, Vec3::Zero());
    hand.read(i * 1e-3);
    const double h = i * 1e-3 - (i - 1) * 1e-3;
    v += (h / p.mass_kg) *
         (p.stiffness_n_per_m * (target - x) - p.damping_n_s_per_m * v - p.device_damping_n_s_per_m * v + f);
    x += h * v;
    ASSERT_NEAR((hand.position() - x).norm(), 0.0, 1e-15) << "tick " << i;
  }
}

TEST(VirtualHandDevice, ExactIntegratorMatchesSemiImplicitEulerForSmallSteps) {
  MotionConfig c;
  c.kind = MotionKind::kCircle;
  c.repeat = 0;
  VirtualHandParams fine;
  fine.substep_s = 1e-6;
  VirtualHandParams exact;
  exact.integrator = HandIntegrator::kExactZeroOrderHold;
  VirtualHandDevice a(make_motion(c), fine);
  VirtualHandDevice b(make_motion(c), exact);
  for (int i = 0; i <= 500; ++i) {
    const Vec3 f(0.2 * std::sin(i * 0.01), 0.5, 0.0);
    a.write_force(f, Vec3::Zero());
    b.write_force(f, Vec3::Zero());
    a.read(i * 1e-3);
    b.read(i * 1e-3);
  }
  // Same continuous hand; they differ by the target being held over b's 1 ms substeps.
  EXPECT_NEAR((a.position() - b.position()).norm(), 0.0, 1e-6);

  VirtualHandDevice still(ScriptedMotion::stationary(Vec3::Zero()), exact);
  still.read(0.0);
  for (int i = 1; i <= 5000; ++i) {
    still.write_force(Vec3(0, 1.0, 0), Vec3::Zero());
    still.read(i * 1e-3);
  }
  EXPECT_NEAR((still.position() - Vec3(0, 1.0 / exact.stiffness_n_per_m, 0)).norm(), 0.0, 1e-12);
}

/// A sampled virtual spring F = −K x at T = 1 ms (zero-order hold) on a hand with device
/// damping b and no arm; returns the energy after 3 s relative to the initial energy.
double sampled_spring_energy_ratio(double k_wall, double b_device, HandIntegrator integrator) {
  VirtualHandParams p;
  p.stiffness_n_per_m = 0.0;
  p.damping_n_s_per_m = 0.0;
  p.device_damping_n_s_per_m = b_device;
  p.integrator = integrator;
  VirtualHandDevice hand(ScriptedMotion::stationary(Vec3::Zero()), p);
  hand.reset(0.0, Vec3::Zero(), Vec3(-0.05, 0, 0));
  const double e0 = hand.kinetic_energy();
  for (int i = 1; i <= 3000; ++i) {
    const DeviceReading r = hand.read(i * 1e-3);
    hand.write_force(-k_wall * r.position_m, Vec3::Zero());
  }
  return (hand.kinetic_energy() + 0.5 * k_wall * hand.position().squaredNorm()) / e0;
}

TEST(VirtualHandDevice, ExactHandShowsColgatesPassivityBound) {
  // b > K·T/2: energy drains; b < K·T/2: the sampled spring pumps energy in.
  constexpr auto kExact = HandIntegrator::kExactZeroOrderHold;
  EXPECT_LT(sampled_spring_energy_ratio(4000.0, 2.2, kExact), 0.1);  // K·T/2 = 2
  EXPECT_GT(sampled_spring_energy_ratio(4000.0, 1.8, kExact), 10.0);
  EXPECT_LT(sampled_spring_energy_ratio(2000.0, 1.1, kExact), 0.1);  // K·T/2 = 1
  EXPECT_GT(sampled_spring_energy_ratio(2000.0, 0.9, kExact), 10.0);
  // Semi-implicit Euler with one substep per period hides the instability (see the header).
  EXPECT_LT(sampled_spring_energy_ratio(4000.0, 1.8, HandIntegrator::kSemiImplicitEuler), 1e-6);
}

}  // namespace
}  // namespace hof::haptics
