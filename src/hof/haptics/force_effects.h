#pragma once
/// @file
/// H3D force effects, added to the surface force each tick (field names and defaults from
/// H3D API 2.x):
///  - SpringEffect: F = k (p − x) − d v, active once the device comes within startDistance of
///    p and until it leaves escapeDistance (springConstant 100 N/m, 0.01 m / 0.01 m, damping 0);
///  - ViscosityEffect: Stokes drag F = −dampingFactor · 6π μ r · v (viscosity 0.01 Pa·s,
///    radius 0.0025 m, dampingFactor 0.5);
///  - ForceField: a constant force (0 0 0 N).

#include <cstdint>
#include <vector>

#include "hof/core/types.h"

namespace hof::haptics {

struct SpringEffect {
  Vec3 position_m{Vec3::Zero()};
  double spring_constant_n_per_m{100.0};
  double start_distance_m{0.01};
  double escape_distance_m{0.01};
  double damping_n_s_per_m{0.0};
  bool active{false};  ///< state: whether the spring currently holds the device
};

struct ViscosityEffect {
  double viscosity_pa_s{0.01};
  double radius_m{0.0025};
  double damping_factor{0.5};
  bool enabled{true};
};

struct ConstantForceEffect {
  Vec3 force_n{Vec3::Zero()};
};

/// The effects of one device, evaluated in the haptic tick (no allocation).
struct ForceEffects {
  std::vector<SpringEffect> springs;
  std::vector<ViscosityEffect> viscosities;
  std::vector<ConstantForceEffect> constants;

  /// Sum of all effect forces at device position x and velocity v (world frame). Updates the
  /// springs' active state.
  Vec3 evaluate(const Vec3& x, const Vec3& v);
};

}  // namespace hof::haptics
