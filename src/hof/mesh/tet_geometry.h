#pragma once
/// @file
/// Geometric measures of a single linear tetrahedron: signed volume, dihedral angles and the
/// normalised radius ratio. Free functions over four corner positions (metres).

#include <array>

#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh {

/// Signed volume (m^3): (b-a)·((c-a)×(d-a)) / 6. Positive for a positively oriented tet.
[[nodiscard]] double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// The six dihedral angles (radians, in [0, π]) at the edges 01, 02, 03, 12, 13, 23.
/// Degenerate (zero-area) faces give 0 for the angles they take part in.
[[nodiscard]] std::array<double, 6> tet_dihedral_angles(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Smallest dihedral angle (radians). A regular tetrahedron has acos(1/3) ≈ 70.53°;
/// slivers approach 0.
[[nodiscard]] double tet_min_dihedral_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Normalised radius ratio 3·r_in / R_circ in [0, 1]: 1 for a regular tetrahedron, 0 for a
/// degenerate one (Shewchuk, "What is a good linear finite element?", 2002).
[[nodiscard]] double tet_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Corner positions of tet `t` of `nodes`.
[[nodiscard]] inline std::array<Vec3, 4> tet_corners(const std::vector<Vec3>& nodes, const Tet& t) {
  return {nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]};
}

}  // namespace hof::mesh
