#include "hof/haptics/force_effects.h"

#include <array>
#include <limits>
#include <numbers>

#include "hof/collision/triangle_queries.h"

namespace hof::haptics {

bool ForceEffects::empty() const {
  return springs.empty() && viscosities.empty() && constants.empty() && magnets.empty() && position_functions.empty() &&
         time_functions.empty();
}

Vec3 ForceEffects::evaluate(const Vec3& x, const Vec3& v, double time_s) {
  Vec3 total = Vec3::Zero();
  for (SpringEffect& s : springs) {
    const double distance = (s.position_m - x).norm();
    if (!s.active && distance <= s.start_distance_m)
      s.active = true;
    else if (s.active && distance > s.escape_distance_m)
      s.active = false;
    if (s.active) total += s.spring_constant_n_per_m * (s.position_m - x) - s.damping_n_s_per_m * v;
  }
  for (const ViscosityEffect& e : viscosities) {
    // Stokes' law for a sphere of radius r in a fluid of viscosity μ: F = −6π μ r v.
    if (e.enabled) total -= e.damping_factor * 6.0 * std::numbers::pi * e.viscosity_pa_s * e.radius_m * v;
  }
  for (const ConstantForceEffect& c : constants) total += c.force_n;
  for (MagneticGeometryEffect& m : magnets) {
    if (!m.enabled || !m.surface) continue;
    // The closest point over every triangle (a bounded loop: validate_effects caps the count).
    const mesh::TriMesh& s = *m.surface;
    Vec3 closest = x;
    double best = std::numeric_limits<double>::infinity();
    Vec3 barycentric;
    for (const mesh::Tri& t : s.triangles) {
      const Vec3 c = collision::detail::closest_point_on_triangle(
          x, s.vertices[static_cast<std::size_t>(t[0])], s.vertices[static_cast<std::size_t>(t[1])],
          s.vertices[static_cast<std::size_t>(t[2])], barycentric);
      const double d = (c - x).squaredNorm();
      if (d < best) {
        best = d;
        closest = c;
      }
    }
    // H3D MagneticGeometryEffect::traverseSG: caught at distance ≤ startDistance, held until
    // distance ≥ escapeDistance.
    const double distance = std::sqrt(best);
    if (!m.active && distance <= m.start_distance_m)
      m.active = true;
    else if (m.active && distance >= m.escape_distance_m)
      m.active = false;
    if (m.active) total += m.spring_constant_n_per_m * (closest - x);
  }
  const std::array<double, 3> position{x.x(), x.y(), x.z()};
  for (const PositionFunctionEffect& f : position_functions)
    total += Vec3(f.fx.evaluate(position), f.fy.evaluate(position), f.fz.evaluate(position));
  const std::array<double, 1> time{time_s};
  for (const TimeFunctionEffect& f : time_functions)
    total += Vec3(f.fx.evaluate(time), f.fy.evaluate(time), f.fz.evaluate(time));
  return total;
}

}  // namespace hof::haptics
