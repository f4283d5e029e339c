#pragma once
/// @file
/// Colour maps for scalar fields drawn on a body (displacement, stress).

#include <Eigen/Core>

namespace hof::render {

/// Perceptually uniform map (a piecewise-linear fit of matplotlib's viridis at 9 stops) of
/// t in [0, 1] (clamped) to RGB.
[[nodiscard]] Eigen::Vector3f viridis(float t);

}  // namespace hof::render
