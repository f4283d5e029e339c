#pragma once
/// @file
/// Fixed-size linear-algebra types used across HoF. All quantities are SI (m, kg, s, N).

#include <Eigen/Dense>

namespace hof {

using Vec3 = Eigen::Vector3d;  ///< a point or vector in R^3, metres unless stated
using Vec3f = Eigen::Vector3f;
using Mat3 = Eigen::Matrix3d;

}  // namespace hof
