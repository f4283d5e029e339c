#pragma once
/// @file
/// Exact per-triangle and per-box geometric queries behind AabbTree (internal to the collision
/// module). Every function is allocation-free and never throws. Degenerate triangles
/// (|(p1−p0)×(p2−p0)| ≤ 1e-12·(longest edge)², or a non-finite coordinate) never produce a
/// contact or a closest point that counts, so no NaN reaches a result.
///
/// Sources (re-derived and written for HoF, no code copied):
///   * C. Ericson, "Real-Time Collision Detection", Morgan Kaufmann 2005:
///     §5.1.5 closest point on a triangle (Voronoi regions), §5.1.3 point–AABB distance,
///     §5.3.3 ray/segment–AABB slab test, §5.3.7 ray–cylinder, §5.3.2 ray–sphere.
///   * T. Möller, B. Trumbore, "Fast, minimum storage ray/triangle intersection",
///     Journal of Graphics Tools 2(1), 1997.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

#include "hof/collision/triangle_mesh_view.h"
#include "hof/core/types.h"

namespace hof::collision::detail {

/// A contact with one triangle along a motion a + t·d, t ∈ [0, 1].
struct TriangleContact {
  double t{1.0};                   ///< fraction of the motion at contact
  Vec3 point{Vec3::Zero()};        ///< contact point on the triangle, m
  Vec3 barycentric{Vec3::Zero()};  ///< weights of the triangle's vertices (p0, p1, p2)
  Vec3 normal{Vec3::Zero()};       ///< unit, from `point` toward the moving point/centre
  bool front{true};                ///< touched from the side the face normal points to
};

/// Closest point of the triangle (p0, p1, p2) to `p` (Ericson §5.1.5): the Voronoi region of
/// `p` (vertex, edge or face) is found from six dot products. Writes the barycentric weights
/// of the result to `barycentric` (sum 1). For a degenerate triangle the result may be NaN
/// (a 0/0 division), never a crash.
[[nodiscard]] Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                             Vec3& barycentric);

/// Whether a closest point found on this triangle counts for AabbTree::closest_point: the
/// triangle is not degenerate and `p` lies on a side `face` allows (front: (p − p0)·n ≥ 0,
/// n = (p1−p0)×(p2−p0)). Checked only for a triangle that would be the new nearest (most
/// lose on distance first); the point from a degenerate triangle may be NaN, which never wins.
[[nodiscard]] bool closest_point_counts(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                        TouchableFace face);

/// Segment a → a + d against a triangle (Möller–Trumbore), both endpoints and the triangle
/// boundary inclusive. Entering from the front means d·n < 0 (n = (p1−p0)×(p2−p0)); `face`
/// filters by that. A segment parallel to the plane never hits. Returns false for a
/// degenerate triangle.
[[nodiscard]] bool intersect_segment_triangle(const Vec3& a, const Vec3& d, const Vec3& p0, const Vec3& p1,
                                              const Vec3& p2, TouchableFace face, TriangleContact& contact);

/// First contact of a sphere of `radius` (≥ 0) whose centre moves from a to a + d with the
/// triangle: the face plane (offset by ±radius, contact inside the triangle), the three edge
/// capsules (ray vs infinite cylinder, then the contact must project inside the edge) and
/// the three vertex spheres (the capsules' end caps); the earliest time wins. The distance
/// from a point moving on a line to a convex set is a convex function of t, so the first
/// time it reaches `radius` while decreasing is unique; a sphere that already overlaps the
/// triangle at a and approaches it (d·normal < 0) touches at t = 0, one that does not
/// approach never touches it.
/// The side: the contact is on the front when the centre lies on the front half-space at
/// contact (normal·n > 0; on the plane itself, when d·n ≤ 0). For a face contact this is
/// exactly "the motion enters from the front" (d·n < 0). `face` filters by it.
[[nodiscard]] bool sweep_sphere_triangle(const Vec3& a, const Vec3& d, double radius, const Vec3& p0, const Vec3& p1,
                                         const Vec3& p2, TouchableFace face, TriangleContact& contact);

/// Closest points of the segments p0–p1 and q0–q1 (Ericson §5.1.9): the parameters s, t ∈ [0, 1]
/// of the points p0 + s·(p1 − p0) and q0 + t·(q1 − q0) that minimise their distance, found by
/// solving the 2×2 normal equations for the infinite lines and clamping (re-solving the other
/// parameter after a clamp). Parallel segments (|d1×d2|² ≤ 1e-12·|d1|²·|d2|²) and degenerate
/// ones have no unique pair: s is first fixed at 0, so one of s, t ends at an endpoint (0 or
/// 1). Gives the squared distance; NaN input gives NaN (never a crash).
struct SegmentClosest {
  double s{0.0};
  double t{0.0};
  Vec3 on_p{Vec3::Zero()};
  Vec3 on_q{Vec3::Zero()};
  double distance_squared{0.0};
};
[[nodiscard]] SegmentClosest closest_points_segment_segment(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                                            const Vec3& q1);

/// Squared distance from `p` to the box [lo, hi] (0 inside), Ericson §5.1.3. Branch-free
/// (max instructions): traversal evaluates it twice per node. NaN input gives NaN.
[[nodiscard]] inline double box_distance_squared(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return ((lo - p).cwiseMax(0.0) + (p - hi).cwiseMax(0.0)).squaredNorm();
}

/// A segment a → a + d prepared for slab tests: the reciprocal of each direction component,
/// or a flag where the component is 0 (then the test checks that a lies inside the slab;
/// multiplying by an infinite reciprocal would give 0·∞ = NaN on a slab boundary).
struct SlabSegment {
  Vec3 origin{Vec3::Zero()};
  Vec3 inv_direction{Vec3::Zero()};
  std::array<bool, 3> flat{};

  SlabSegment() = default;
  SlabSegment(const Vec3& a, const Vec3& d) : origin(a) {
    for (int i = 0; i < 3; ++i) {
      flat[i] = d[i] == 0.0;
      inv_direction[i] = flat[i] ? 0.0 : 1.0 / d[i];
    }
  }
};

/// Slab test (Ericson §5.3.3, Kay–Kajiya slabs) of the segment against the box
/// [lo − inflate, hi + inflate] for t ∈ [0, t_max]: on overlap writes the entry time
/// (0 when `origin` is inside) and returns true. Boundaries are inclusive. Written without
/// data-dependent branches (min/max and selects; one test at the end): during traversal the
/// outcome is unpredictable, and mispredictions would dominate the cost.
[[nodiscard]] inline bool slab_entry(const SlabSegment& s, const Vec3& lo, const Vec3& hi, double inflate, double t_max,
                                     double& t_enter) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double t0 = 0.0;
  double t1 = t_max;
  bool inside_flat_slabs = true;
  for (int i = 0; i < 3; ++i) {
    const double l = lo[i] - inflate;
    const double h = hi[i] + inflate;
    const double ta = (l - s.origin[i]) * s.inv_direction[i];
    const double tb = (h - s.origin[i]) * s.inv_direction[i];
    // A flat axis does not bound t; the origin must lie in its slab instead.
    const double t_near = s.flat[i] ? -kInf : std::min(ta, tb);
    const double t_far = s.flat[i] ? kInf : std::max(ta, tb);
    t0 = std::max(t0, t_near);
    t1 = std::min(t1, t_far);
    inside_flat_slabs &= !s.flat[i] || (s.origin[i] >= l && s.origin[i] <= h);
  }
  t_enter = t0;
  return inside_flat_slabs && t0 <= t1;
}

}  // namespace hof::collision::detail

namespace hof::collision {

/// Squared distance from `p` to the triangle (p0, p1, p2) (its closest point: Ericson §5.1.5);
/// NaN for a degenerate triangle.
[[nodiscard]] double point_triangle_distance_squared(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2);

}  // namespace hof::collision
