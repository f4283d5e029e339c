#pragma once
/// @file
/// Haptic surface properties, after H3D's surface nodes (field names and defaults from
/// H3D API 2.x, see shared/reference/h3d-nodes.md) and HAPI's FrictionSurface force law:
///   F = k (proxy − probe) − d ((n̂·v) n̂),  n̂ = unit vector from the probe to the proxy,
/// with friction after Ruspini, Kolarov & Khatib 1997, §4: the contact sticks while the
/// tangential force stays within μs times the normal force, and slides at
/// v = (Ft − μd·Fn)/b (b = 1 N·s/m) otherwise.

#include <cstdint>

#include "hof/core/error.h"

namespace hof::haptics {

enum class SurfaceKind : std::uint8_t {
  kSmooth,      ///< SmoothSurface: stiffness, damping; frictionless
  kFrictional,  ///< FrictionalSurface: + staticFriction, dynamicFriction
  kMagnetic,    ///< MagneticSurface: + snapDistance (the proxy is held to the surface)
  kZeroForce,   ///< the thesis' LiverSurface: proxy tracks the surface, no force (needles)
};

struct SurfaceMaterial {
  SurfaceKind kind{SurfaceKind::kSmooth};
  /// H3D `stiffness`: a fraction of the device's max stiffness when use_relative_values
  /// (H3D default 0.5, relative), else N/m.
  double stiffness{0.5};
  double damping_n_s_per_m{0.0};   ///< H3D `damping` (always absolute)
  bool use_relative_values{true};  ///< H3D `useRelativeValues`
  double static_friction{0.1};     ///< H3D `staticFriction` (FrictionalSurface default)
  double dynamic_friction{0.4};    ///< H3D `dynamicFriction`
  double snap_distance_m{0.01};    ///< H3D MagneticSurface `snapDistance`

  /// Stiffness in N/m for a device whose maximum stable stiffness is given.
  [[nodiscard]] double stiffness_n_per_m(double device_max_stiffness) const {
    return use_relative_values ? stiffness * device_max_stiffness : stiffness;
  }
  /// Whether friction applies (frictional and magnetic surfaces with non-zero coefficients).
  [[nodiscard]] bool has_friction() const {
    return (kind == SurfaceKind::kFrictional || kind == SurfaceKind::kMagnetic) &&
           (static_friction > 0.0 || dynamic_friction > 0.0);
  }
};

/// Checks ranges (stiffness ≥ 0, friction in [0, 1], snap distance ≥ 0); the error names the
/// field.
[[nodiscard]] Expected<SurfaceMaterial> validate(const SurfaceMaterial& material);

}  // namespace hof::haptics
