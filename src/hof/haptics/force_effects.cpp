#include "hof/haptics/force_effects.h"

#include <numbers>

namespace hof::haptics {

Vec3 ForceEffects::evaluate(const Vec3& x, const Vec3& v) {
  Vec3 total = Vec3::Zero();
  for (SpringEffect& s : springs) {
    const double distance = (s.position_m - x).norm();
    if (!s.active && distance <= s.start_distance_m) s.active = true;
    else if (s.active && distance > s.escape_distance_m) s.active = false;
    if (s.active) total += s.spring_constant_n_per_m * (s.position_m - x) - s.damping_n_s_per_m * v;
  }
  for (const ViscosityEffect& e : viscosities) {
    // Stokes' law for a sphere of radius r in a fluid of viscosity μ: F = −6π μ r v.
    if (e.enabled) total -= e.damping_factor * 6.0 * std::numbers::pi * e.viscosity_pa_s * e.radius_m * v;
  }
  for (const ConstantForceEffect& c : constants) total += c.force_n;
  return total;
}

}  // namespace hof::haptics
