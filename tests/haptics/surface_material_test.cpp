// Haptic surface properties (src/hof/haptics/surface_material.cpp): H3D's defaults, relative
// and absolute stiffness, which kinds have friction, and validation naming the bad field.

#include "hof/haptics/surface_material.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>

namespace hof::haptics {
namespace {

constexpr double kNotANumber = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinite = std::numeric_limits<double>::infinity();

TEST(SurfaceMaterial, StiffnessIsAFractionOfTheDevicesUnlessAbsolute) {
  SurfaceMaterial m;  // H3D: 0.5, relative
  EXPECT_EQ(m.stiffness_n_per_m(3000.0), 1500.0);
  m.use_relative_values = false;
  m.stiffness = 800.0;
  EXPECT_EQ(m.stiffness_n_per_m(3000.0), 800.0);
}

TEST(SurfaceMaterial, OnlyFrictionalAndMagneticSurfacesWithACoefficientHaveFriction) {
  SurfaceMaterial m;
  for (const SurfaceKind kind : {SurfaceKind::kSmooth, SurfaceKind::kZeroForce}) {
    m.kind = kind;
    EXPECT_FALSE(m.has_friction());
  }
  for (const SurfaceKind kind : {SurfaceKind::kFrictional, SurfaceKind::kMagnetic}) {
    m.kind = kind;
    m.static_friction = 0.1;
    m.dynamic_friction = 0.0;
    EXPECT_TRUE(m.has_friction());
    m.static_friction = 0.0;
    m.dynamic_friction = 0.4;
    EXPECT_TRUE(m.has_friction());
    m.dynamic_friction = 0.0;
    EXPECT_FALSE(m.has_friction());
  }
}

TEST(SurfaceMaterial, ValidAtTheEdgesOfEveryRange) {
  SurfaceMaterial m;
  EXPECT_TRUE(validate(m));
  m.stiffness = 0.0;
  m.damping_n_s_per_m = 0.0;
  m.static_friction = 1.0;
  m.dynamic_friction = 0.0;
  m.snap_distance_m = 0.0;
  const auto ok = validate(m);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->static_friction, 1.0);
}

TEST(SurfaceMaterial, EachBadFieldIsNamedWithItsRange) {
  struct Case {
    std::function<void(SurfaceMaterial&)> spoil;
    std::string message;
  };
  const Case cases[] = {
      {[](SurfaceMaterial& m) { m.stiffness = -1.0; }, "stiffness must be >= 0, got -1"},
      {[](SurfaceMaterial& m) { m.stiffness = kNotANumber; }, "stiffness must be >= 0"},
      {[](SurfaceMaterial& m) { m.stiffness = kInfinite; }, "stiffness must be >= 0, got inf"},
      {[](SurfaceMaterial& m) { m.damping_n_s_per_m = -0.5; }, "damping must be >= 0, got -0.5"},
      {[](SurfaceMaterial& m) { m.static_friction = 1.5; }, "staticFriction must be in [0, 1], got 1.5"},
      {[](SurfaceMaterial& m) { m.dynamic_friction = -0.1; }, "dynamicFriction must be in [0, 1], got -0.1"},
      {[](SurfaceMaterial& m) { m.dynamic_friction = kNotANumber; }, "dynamicFriction must be in [0, 1]"},
      {[](SurfaceMaterial& m) { m.snap_distance_m = kInfinite; }, "snapDistance must be >= 0 m"},
  };
  for (const Case& c : cases) {
    SurfaceMaterial m;
    c.spoil(m);
    const auto r = validate(m);
    ASSERT_FALSE(r) << c.message;
    EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(r.error().to_string().find(c.message), std::string::npos) << r.error().to_string();
  }
}

}  // namespace
}  // namespace hof::haptics
