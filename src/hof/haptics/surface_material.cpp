#include "hof/haptics/surface_material.h"

#include <fmt/format.h>

#include <cmath>

namespace hof::haptics {

Expected<SurfaceMaterial> validate(const SurfaceMaterial& m) {
  auto bad = [](const char* field, double value, const char* range) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("surface: {} must be {}, got {}", field, range, value));
  };
  if (!(m.stiffness >= 0.0) || !std::isfinite(m.stiffness)) return bad("stiffness", m.stiffness, ">= 0");
  if (!(m.damping_n_s_per_m >= 0.0) || !std::isfinite(m.damping_n_s_per_m))
    return bad("damping", m.damping_n_s_per_m, ">= 0");
  if (!(m.static_friction >= 0.0 && m.static_friction <= 1.0))
    return bad("staticFriction", m.static_friction, "in [0, 1]");
  if (!(m.dynamic_friction >= 0.0 && m.dynamic_friction <= 1.0))
    return bad("dynamicFriction", m.dynamic_friction, "in [0, 1]");
  if (!(m.snap_distance_m >= 0.0) || !std::isfinite(m.snap_distance_m))
    return bad("snapDistance", m.snap_distance_m, ">= 0 m");
  return m;
}

}  // namespace hof::haptics
