// H3D force effects (src/hof/haptics/force_effects.cpp): each force law against values worked
// out by hand (N, m, s), its sign (springs and magnets pull toward their anchor, drag opposes
// the motion), the catch and release distances, and the sum over effects.

#include "hof/haptics/force_effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace hof::haptics {
namespace {

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
  EXPECT_EQ(effects.evaluate(Vec3(0.025, 0, 0), Vec3::Zero()), Vec3::Zero());                 // escaped
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

TEST(ForceEffects, SpringIsStiffnessTimesOffsetMinusDampingTimesVelocity) {
  // p − x = (−0.002, 0.002, −0.001) m, |p − x| = 3 mm: caught.
  // F = 250 (p − x) − 2 v = (−0.5, 0.5, −0.25) − (0.2, −0.4, 0.1) = (−0.7, 0.9, −0.35) N.
  ForceEffects effects;
  SpringEffect spring;
  spring.position_m = Vec3(0.01, 0.02, -0.005);
  spring.spring_constant_n_per_m = 250.0;
  spring.damping_n_s_per_m = 2.0;
  effects.springs.push_back(spring);
  const Vec3 f = effects.evaluate(Vec3(0.012, 0.018, -0.004), Vec3(0.1, -0.2, 0.05));
  EXPECT_NEAR(f.x(), -0.7, 1e-12);
  EXPECT_NEAR(f.y(), 0.9, 1e-12);
  EXPECT_NEAR(f.z(), -0.35, 1e-12);
  EXPECT_TRUE(effects.springs[0].active);
}

TEST(ForceEffects, SpringPullsTowardItsAnchorFromEverySide) {
  ForceEffects effects;
  SpringEffect spring;
  spring.position_m = Vec3(0.1, -0.2, 0.3);
  spring.start_distance_m = spring.escape_distance_m = 0.05;
  effects.springs.push_back(spring);
  for (const Vec3& dir : {Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(-1, 1, -1).normalized()}) {
    const Vec3 x = spring.position_m + 0.02 * dir;
    const Vec3 f = effects.evaluate(x, Vec3::Zero());
    EXPECT_NEAR(f.norm(), 100.0 * 0.02, 1e-12);         // H3D default 100 N/m
    EXPECT_NEAR(f.normalized().dot(-dir), 1.0, 1e-12);  // restoring
  }
}

TEST(ForceEffects, SpringCatchesAtStartDistanceInclusiveAndHoldsUpToEscapeDistanceInclusive) {
  ForceEffects effects;
  SpringEffect spring;
  spring.start_distance_m = 0.25;  // binary fractions: the distances compare exactly
  spring.escape_distance_m = 0.5;
  effects.springs.push_back(spring);
  EXPECT_EQ(effects.evaluate(Vec3(0.3, 0, 0), Vec3::Zero()), Vec3::Zero());
  EXPECT_FALSE(effects.springs[0].active);
  EXPECT_EQ(effects.evaluate(Vec3(0, 0.25, 0), Vec3::Zero()), Vec3(0, -25.0, 0));  // exactly at start
  EXPECT_EQ(effects.evaluate(Vec3(0, 0, 0.5), Vec3::Zero()), Vec3(0, 0, -50.0));   // exactly at escape: held
  EXPECT_EQ(effects.evaluate(Vec3(0, 0, 0.5000001), Vec3::Zero()), Vec3::Zero());  // past it: let go
  EXPECT_FALSE(effects.springs[0].active);
  // Let go, it does not catch again between start and escape.
  EXPECT_EQ(effects.evaluate(Vec3(0.3, 0, 0), Vec3::Zero()), Vec3::Zero());
}

TEST(ForceEffects, ViscosityIsLinearInVelocityAndOpposesIt) {
  ForceEffects effects;
  ViscosityEffect e;
  e.viscosity_pa_s = 0.02;
  e.radius_m = 0.01;
  e.damping_factor = 1.0;
  effects.viscosities.push_back(e);
  const double b = 6.0 * std::numbers::pi * 0.02 * 0.01;  // 3.77e-3 N·s/m
  const Vec3 v(1.0, -2.0, 3.0);
  const Vec3 f = effects.evaluate(Vec3(5, 5, 5), v);
  EXPECT_LT((f + b * v).norm(), 1e-15);
  EXPECT_LT(f.dot(v), 0.0);
  EXPECT_LT((effects.evaluate(Vec3::Zero(), 2.0 * v) - 2.0 * f).norm(), 1e-15);
  EXPECT_EQ(effects.evaluate(Vec3::Zero(), Vec3::Zero()), Vec3::Zero());
  effects.viscosities[0].enabled = false;
  EXPECT_EQ(effects.evaluate(Vec3::Zero(), v), Vec3::Zero());
}

TEST(ForceEffects, ConstantForcesAddAndIgnoreTheDevice) {
  ForceEffects effects;
  effects.constants.push_back(ConstantForceEffect{Vec3(1.0, 0.0, -0.5)});
  effects.constants.push_back(ConstantForceEffect{Vec3(0.25, 2.0, 0.5)});
  for (const Vec3& x : {Vec3(Vec3::Zero()), Vec3(1, -1, 3)}) {
    EXPECT_EQ(effects.evaluate(x, Vec3(4, 5, 6)), Vec3(1.25, 2.0, 0.0));
  }
}

// A 0.2 m square in the plane z = 0, two triangles, normals up.
std::shared_ptr<const mesh::TriMesh> square_surface() {
  auto m = std::make_shared<mesh::TriMesh>();
  m->vertices = {Vec3(0, 0, 0), Vec3(0.2, 0, 0), Vec3(0.2, 0.2, 0), Vec3(0, 0.2, 0)};
  m->triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(ForceEffects, MagnetPullsTowardTheClosestPointOfItsSurface) {
  ForceEffects effects;
  MagneticGeometryEffect magnet;
  magnet.surface = square_surface();
  magnet.spring_constant_n_per_m = 400.0;
  magnet.start_distance_m = 0.02;
  magnet.escape_distance_m = 0.03;
  effects.magnets.push_back(magnet);
  // Above the face: straight down, k·h.
  Vec3 f = effects.evaluate(Vec3(0.05, 0.12, 0.01), Vec3(1, 1, 1));  // the velocity plays no part
  EXPECT_NEAR(f.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.y(), 0.0, 1e-12);
  EXPECT_NEAR(f.z(), -400.0 * 0.01, 1e-12);
  // Beside the edge x = 0.2, 0.01 out and 0.01 up: toward the edge point (0.2, 0.1, 0).
  f = effects.evaluate(Vec3(0.21, 0.1, 0.01), Vec3::Zero());
  EXPECT_NEAR(f.x(), -4.0, 1e-12);
  EXPECT_NEAR(f.y(), 0.0, 1e-12);
  EXPECT_NEAR(f.z(), -4.0, 1e-12);
  // Off the corner (0, 0, 0).
  f = effects.evaluate(Vec3(-0.01, -0.01, 0.0), Vec3::Zero());
  EXPECT_NEAR(f.x(), 4.0, 1e-12);
  EXPECT_NEAR(f.y(), 4.0, 1e-12);
  EXPECT_NEAR(f.z(), 0.0, 1e-12);
}

TEST(ForceEffects, MagnetCatchesWithinStartAndLetsGoAtEscape) {
  ForceEffects effects;
  MagneticGeometryEffect magnet;
  magnet.surface = square_surface();
  magnet.start_distance_m = 0.25;
  magnet.escape_distance_m = 0.5;
  effects.magnets.push_back(magnet);
  EXPECT_EQ(effects.evaluate(Vec3(0.1, 0.05, 0.375), Vec3::Zero()), Vec3::Zero());        // not caught yet
  EXPECT_NEAR(effects.evaluate(Vec3(0.1, 0.05, 0.24), Vec3::Zero()).z(), -24.0, 1e-12);   // caught
  EXPECT_NEAR(effects.evaluate(Vec3(0.1, 0.05, 0.375), Vec3::Zero()).z(), -37.5, 1e-12);  // held
  EXPECT_NEAR(effects.evaluate(Vec3(0.1, 0.05, 0.49), Vec3::Zero()).z(), -49.0, 1e-12);   // held
  // Unlike the spring (released past escape), H3D's magnet lets go at escape itself.
  EXPECT_EQ(effects.evaluate(Vec3(0.1, 0.05, 0.5), Vec3::Zero()), Vec3::Zero());
  EXPECT_FALSE(effects.magnets[0].active);
}

TEST(ForceEffects, ADisabledMagnetOrOneWithoutASurfaceGivesNoForce) {
  ForceEffects effects;
  MagneticGeometryEffect magnet;
  magnet.surface = square_surface();
  magnet.enabled = false;
  effects.magnets.push_back(magnet);
  effects.magnets.push_back(MagneticGeometryEffect{});  // no surface
  EXPECT_EQ(effects.evaluate(Vec3(0.1, 0.1, 0.001), Vec3::Zero()), Vec3::Zero());
  EXPECT_FALSE(effects.magnets[0].active);
  EXPECT_FALSE(effects.magnets[1].active);
}

FunctionExpression function(const std::string& text, std::vector<std::string> variables) {
  auto f = FunctionExpression::make(text, variables);
  EXPECT_TRUE(f.has_value()) << text;
  return f ? *f : FunctionExpression{};
}

TEST(ForceEffects, PositionFunctionsTakeTheDevicePositionInMetres) {
  ForceEffects effects;
  const std::vector<std::string> xyz{"x", "y", "z"};
  effects.position_functions.push_back(
      PositionFunctionEffect{function("10*y", xyz), function("-10*x", xyz), function("x*y*z + 1", xyz)});
  const Vec3 f = effects.evaluate(Vec3(0.5, 0.25, 2.0), Vec3(9, 9, 9), 7.0);
  EXPECT_DOUBLE_EQ(f.x(), 2.5);
  EXPECT_DOUBLE_EQ(f.y(), -5.0);
  EXPECT_DOUBLE_EQ(f.z(), 1.25);
}

TEST(ForceEffects, TimeFunctionsTakeTheSessionTimeInSeconds) {
  ForceEffects effects;
  const std::vector<std::string> t{"t"};
  effects.time_functions.push_back(TimeFunctionEffect{function("sin(t)", t), function("2*t", t), function("0", t)});
  const double time = 0.3;
  const Vec3 f = effects.evaluate(Vec3(1, 2, 3), Vec3::Zero(), time);
  EXPECT_DOUBLE_EQ(f.x(), std::sin(time));
  EXPECT_DOUBLE_EQ(f.y(), 0.6);
  EXPECT_EQ(f.z(), 0.0);
}

TEST(ForceEffects, TheTotalIsTheSumOfEachEffectAlone) {
  SpringEffect spring;
  spring.position_m = Vec3(0.001, 0, 0);
  spring.damping_n_s_per_m = 0.5;
  ViscosityEffect viscosity;
  ConstantForceEffect constant{Vec3(0, 0, -0.3)};
  const Vec3 x(0.003, 0.002, -0.001), v(0.05, -0.02, 0.01);
  ForceEffects all;
  all.springs.push_back(spring);
  all.viscosities.push_back(viscosity);
  all.constants.push_back(constant);
  ForceEffects only_spring, only_viscosity, only_constant;
  only_spring.springs.push_back(spring);
  only_viscosity.viscosities.push_back(viscosity);
  only_constant.constants.push_back(constant);
  const Vec3 sum = only_spring.evaluate(x, v) + only_viscosity.evaluate(x, v) + only_constant.evaluate(x, v);
  EXPECT_LT((all.evaluate(x, v) - sum).norm(), 1e-15);
}

TEST(ForceEffects, EmptyOnlyWithoutAnyEffect) {
  ForceEffects effects;
  EXPECT_TRUE(effects.empty());
  EXPECT_EQ(effects.evaluate(Vec3(1, 2, 3), Vec3(4, 5, 6), 7.0), Vec3::Zero());
  const auto with = [](auto add) {
    ForceEffects e;
    add(e);
    return e.empty();
  };
  EXPECT_FALSE(with([](ForceEffects& e) { e.springs.emplace_back(); }));
  EXPECT_FALSE(with([](ForceEffects& e) { e.viscosities.emplace_back(); }));
  EXPECT_FALSE(with([](ForceEffects& e) { e.constants.emplace_back(); }));
  EXPECT_FALSE(with([](ForceEffects& e) { e.magnets.emplace_back(); }));
  EXPECT_FALSE(with([](ForceEffects& e) { e.position_functions.emplace_back(); }));
  EXPECT_FALSE(with([](ForceEffects& e) { e.time_functions.emplace_back(); }));
}

}  // namespace
}  // namespace hof::haptics
