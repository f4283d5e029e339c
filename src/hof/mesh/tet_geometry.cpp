#include "hof/mesh/tet_geometry.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace hof::mesh {

double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

std::array<double, 6> tet_dihedral_angles(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  // Area vectors of the faces opposite each corner, all pointing the same way relative to the
  // tet (outward for positive orientation). The dihedral angle at the edge shared by the faces
  // opposite corners k and l is π minus the angle between their outward normals.
  const std::array<Vec3, 4> n = {
      (c - b).cross(d - b),  // opposite a
      (d - a).cross(c - a),  // opposite b
      (b - a).cross(d - a),  // opposite c
      (c - a).cross(b - a),  // opposite d
  };
  // Edge (i,j) is shared by the faces opposite the two other corners (k,l).
  constexpr std::array<std::array<int, 2>, 6> kOppositeFaces = {{{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}}};
  std::array<double, 6> angles{};
  for (std::size_t e = 0; e < 6; ++e) {
    const Vec3& nk = n[kOppositeFaces[e][0]];
    const Vec3& nl = n[kOppositeFaces[e][1]];
    const double denom = nk.norm() * nl.norm();
    if (!(denom > 0.0)) {
      angles[e] = 0.0;
      continue;
    }
    const double cosine = std::clamp(nk.dot(nl) / denom, -1.0, 1.0);
    angles[e] = std::numbers::pi - std::acos(cosine);
  }
  return angles;
}

double tet_min_dihedral_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const auto angles = tet_dihedral_angles(a, b, c, d);
  return *std::min_element(angles.begin(), angles.end());
}

double tet_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double volume = std::abs(tet_signed_volume(a, b, c, d));
  const Vec3 u = b - a, v = c - a, w = d - a;
  const double face_area_sum =
      0.5 * (u.cross(v).norm() + v.cross(w).norm() + w.cross(u).norm() + (c - b).cross(d - b).norm());
  if (!(volume > 0.0) || !(face_area_sum > 0.0)) return 0.0;
  const double r_in = 3.0 * volume / face_area_sum;
  // Circumradius: |‖u‖²(v×w) + ‖v‖²(w×u) + ‖w‖²(u×v)| / (12 V).
  const Vec3 num = u.squaredNorm() * v.cross(w) + v.squaredNorm() * w.cross(u) + w.squaredNorm() * u.cross(v);
  const double r_circ = num.norm() / (12.0 * volume);
  if (!(r_circ > 0.0)) return 0.0;
  return std::clamp(3.0 * r_in / r_circ, 0.0, 1.0);
}

}  // namespace hof::mesh
