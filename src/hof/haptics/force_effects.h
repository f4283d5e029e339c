#pragma once
/// @file
/// H3D force effects, added to the surface force each tick (field names and defaults from
/// H3D API 2.x):
///  - SpringEffect: F = k (p − x) − d v, active once the device comes within startDistance of
///    p and until it leaves escapeDistance (springConstant 100 N/m, 0.01 m / 0.01 m, damping 0);
///  - ViscosityEffect: Stokes drag F = −dampingFactor · 6π μ r · v (viscosity 0.01 Pa·s,
///    radius 0.0025 m, dampingFactor 0.5);
///  - ForceField: a constant force (0 0 0 N);
///  - MagneticGeometryEffect: F = k (c − x), c the closest point of its surface to the device,
///    caught within startDistance, let go past escapeDistance (HAPI HapticShapeConstraint;
///    springConstant 100 N/m as H3D's constructor sets it, 0.01 m / 0.01 m);
///  - PositionFunctionEffect: F = (fx(x, y, z), fy(…), fz(…)), x the device position (world, m);
///  - TimeFunctionEffect: F = (fx(t), fy(t), fz(t)), t the session time, s (HAPI takes the wall
///    clock's seconds since the epoch; a session's own clock keeps runs reproducible).

#include <cstdint>
#include <memory>
#include <vector>

#include "hof/core/types.h"
#include "hof/haptics/function_expression.h"
#include "hof/mesh/mesh.h"

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

struct MagneticGeometryEffect {
  /// The surface it holds to, world frame, m. Shared and never changed once made, so that
  /// copying the effect into the haptic loop does not allocate.
  std::shared_ptr<const mesh::TriMesh> surface;
  double spring_constant_n_per_m{100.0};
  double start_distance_m{0.01};
  double escape_distance_m{0.01};
  bool enabled{true};
  bool active{false};  ///< state: whether it currently holds the device
};

struct PositionFunctionEffect {
  FunctionExpression fx, fy, fz;  ///< of the device position x, y, z (m), in N
};

struct TimeFunctionEffect {
  FunctionExpression fx, fy, fz;  ///< of the time t (s), in N
};

/// The effects of one device, evaluated in the haptic tick (no allocation).
struct ForceEffects {
  std::vector<SpringEffect> springs;
  std::vector<ViscosityEffect> viscosities;
  std::vector<ConstantForceEffect> constants;
  std::vector<MagneticGeometryEffect> magnets;
  std::vector<PositionFunctionEffect> position_functions;
  std::vector<TimeFunctionEffect> time_functions;

  /// Whether there is no effect of any kind.
  [[nodiscard]] bool empty() const;

  /// Sum of all effect forces at device position x and velocity v (world frame) at session
  /// time `time_s`. Updates the springs' and magnets' active state.
  Vec3 evaluate(const Vec3& x, const Vec3& v, double time_s = 0.0);
};

}  // namespace hof::haptics
