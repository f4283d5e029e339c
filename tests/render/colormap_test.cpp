// The viridis colour map (src/hof/render/colormap.cpp): its published end points and stops, linear
// between stops, clamped outside [0, 1], NaN drawn as the low end, and lightness rising with t
// (what makes a scalar field readable).

#include "hof/render/colormap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hof::render {
namespace {

float luminance(const Eigen::Vector3f& c) { return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(); }

TEST(Viridis, EndsAndMiddleAreMatplotlibsValues) {
  EXPECT_EQ(viridis(0.0f), Eigen::Vector3f(0.267f, 0.005f, 0.329f));                   // dark purple
  EXPECT_EQ(viridis(0.5f), Eigen::Vector3f(0.164f, 0.471f, 0.558f));                   // teal
  EXPECT_LT((viridis(1.0f) - Eigen::Vector3f(0.993f, 0.906f, 0.144f)).norm(), 1e-6f);  // yellow
}

TEST(Viridis, IsLinearBetweenStops) {
  const Eigen::Vector3f a = viridis(0.0f), b = viridis(0.125f);
  EXPECT_LT((viridis(0.0625f) - 0.5f * (a + b)).norm(), 1e-6f);
  EXPECT_LT((viridis(0.03125f) - (0.75f * a + 0.25f * b)).norm(), 1e-6f);
}

TEST(Viridis, ClampsOutsideZeroToOneAndDrawsNaNAsTheLowEnd) {
  EXPECT_EQ(viridis(-3.0f), viridis(0.0f));
  EXPECT_EQ(viridis(7.0f), viridis(1.0f));
  EXPECT_EQ(viridis(std::numeric_limits<float>::quiet_NaN()), viridis(0.0f));
  EXPECT_EQ(viridis(std::numeric_limits<float>::infinity()), viridis(0.0f));
}

TEST(Viridis, LightnessRisesWithTAndChannelsStayInRange) {
  float previous = -1.0f;
  for (int i = 0; i <= 1000; ++i) {
    const Eigen::Vector3f c = viridis(static_cast<float>(i) / 1000.0f);
    EXPECT_GE(c.minCoeff(), 0.0f);
    EXPECT_LE(c.maxCoeff(), 1.0f);
    EXPECT_GT(luminance(c), previous) << "t = " << i / 1000.0;
    previous = luminance(c);
  }
}

TEST(Viridis, IsContinuous) {
  // The steepest stretch, the last eighth (red 0.478 → 0.993), moves the colour 0.55 in all.
  for (int i = 0; i < 4000; ++i) {
    const float t = static_cast<float>(i) / 4000.0f;
    EXPECT_LT((viridis(t + 1.0f / 4000.0f) - viridis(t)).norm(), 0.56f * 8.0f / 4000.0f) << t;
  }
}

}  // namespace
}  // namespace hof::render
