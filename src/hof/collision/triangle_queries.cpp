#include "hof/collision/triangle_queries.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hof::collision::detail {
namespace {

// A triangle is degenerate below this ratio of twice its area to its longest edge squared
// (≈ the sine of its smallest angle): its normal and barycentric weights are meaningless.
constexpr double kDegenerateRatio = 1e-12;

// Comparisons below are written so that NaN fails them (`!(x >= 0)` rather than `x < 0`):
// whatever slips through the degeneracy test can only produce "no contact".

bool degenerate_with_normal(const Vec3& p0, const Vec3& p1, const Vec3& p2, Vec3& n_raw) {
  const Vec3 e01 = p1 - p0;
  const Vec3 e02 = p2 - p0;
  const Vec3 e12 = p2 - p1;
  n_raw = e01.cross(e02);
  const double longest2 = std::max({e01.squaredNorm(), e02.squaredNorm(), e12.squaredNorm()});
  const double threshold = kDegenerateRatio * longest2;
  return !(n_raw.squaredNorm() > threshold * threshold);
}

bool touchable(TouchableFace face, bool front) {
  switch (face) {
    case TouchableFace::kFront:
      return front;
    case TouchableFace::kBack:
      return !front;
    case TouchableFace::kFrontAndBack:
      return true;
  }
  return false;
}

// Barycentric weights of a point q of the triangle's plane from sub-triangle areas
// (signed by the face normal); q is inside (boundary included) when all are >= 0.
bool inside_triangle(const Vec3& q, const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& n_raw,
                     Vec3& barycentric) {
  const double inv_area2 = 1.0 / n_raw.squaredNorm();
  const Vec3 to0 = p0 - q;
  const Vec3 to1 = p1 - q;
  const Vec3 to2 = p2 - q;
  barycentric = Vec3(n_raw.dot(to1.cross(to2)), n_raw.dot(to2.cross(to0)), n_raw.dot(to0.cross(to1))) * inv_area2;
  return barycentric.minCoeff() >= 0.0;
}

// Unit vector from the contact point toward the centre. When the centre lies on the
// triangle the direction is the face normal on the side the motion comes from.
Vec3 contact_normal(const Vec3& gap, const Vec3& n, const Vec3& d) {
  const double length = gap.norm();
  if (length > 0.0) return gap / length;
  return d.dot(n) <= 0.0 ? n : Vec3(-n);
}

// Accepts a sphere contact that approaches the triangle from a touchable side.
bool finish_sphere_contact(double t, const Vec3& point, const Vec3& barycentric, const Vec3& m, const Vec3& n,
                           const Vec3& d, TouchableFace face, TriangleContact& contact) {
  if (!(d.dot(m) < 0.0)) return false;  // sliding along or leaving the triangle
  const double side = m.dot(n);
  const bool front = side > 0.0 || (side == 0.0 && d.dot(n) <= 0.0);
  if (!touchable(face, front)) return false;
  contact.t = t;
  contact.point = point;
  contact.barycentric = barycentric;
  contact.normal = m;
  contact.front = front;
  return true;
}

}  // namespace

// Ericson §5.1.5: test the Voronoi regions of the vertices, then of the edges, else the
// face. With ab = p1 − p0, ac = p2 − p0 and the dot products d1..d6 of ab, ac with the
// vectors from each vertex to p, each region is a sign condition; the three "va, vb, vc"
// are the unnormalised barycentric weights of p's projection.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2, Vec3& barycentric) {
  const Vec3 ab = p1 - p0;
  const Vec3 ac = p2 - p0;
  const Vec3 ap = p - p0;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {  // vertex region p0
    barycentric = Vec3(1.0, 0.0, 0.0);
    return p0;
  }
  const Vec3 bp = p - p1;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {  // vertex region p1
    barycentric = Vec3(0.0, 1.0, 0.0);
    return p1;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {  // edge region p0p1; d1 − d3 = |ab|² > 0
    const double v = d1 / (d1 - d3);
    barycentric = Vec3(1.0 - v, v, 0.0);
    return p0 + v * ab;
  }
  const Vec3 cp = p - p2;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {  // vertex region p2
    barycentric = Vec3(0.0, 0.0, 1.0);
    return p2;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {  // edge region p0p2; d2 − d6 = |ac|² > 0
    const double w = d2 / (d2 - d6);
    barycentric = Vec3(1.0 - w, 0.0, w);
    return p0 + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {  // edge region p1p2
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));   // denominator |p2 − p1|²
    barycentric = Vec3(0.0, 1.0 - w, w);
    return p1 + w * (p2 - p1);
  }
  // Face region; va + vb + vc = |ab × ac|² > 0 for a non-degenerate triangle.
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom;
  const double w = vc * denom;
  barycentric = Vec3(1.0 - v - w, v, w);
  return p0 + v * ab + w * ac;
}

bool closest_point_counts(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2, TouchableFace face) {
  Vec3 n_raw;
  if (degenerate_with_normal(p0, p1, p2, n_raw)) return false;
  return face == TouchableFace::kFrontAndBack || touchable(face, (p - p0).dot(n_raw) >= 0.0);
}

// Möller & Trumbore 1997: solve a + t·d = (1−u−v)·p0 + u·p1 + v·p2 by Cramer's rule with
// scalar triple products. det = (p1−p0)·(d × (p2−p0)) = −d·n, so det > 0 is a front entry.
bool intersect_segment_triangle(const Vec3& a, const Vec3& d, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                TouchableFace face, TriangleContact& contact) {
  const Vec3 e1 = p1 - p0;
  const Vec3 e2 = p2 - p0;
  const Vec3 pvec = d.cross(e2);
  const double det = e1.dot(pvec);
  if (!(det > 0.0 || det < 0.0)) return false;  // parallel to the plane (or NaN)
  const bool front = det > 0.0;
  if (!touchable(face, front)) return false;
  const double inv_det = 1.0 / det;
  const Vec3 tvec = a - p0;
  // Watertight across shared edges: a segment through an edge (or a vertex) must hit at least
  // one of the triangles meeting there, whatever the rounding of u and v. Both therefore
  // accept a sliver of 1e-9 beyond their edges; the nearer-t / lower-index tie rule picks one.
  constexpr double kEdgeTolerance = 1e-9;
  double u = tvec.dot(pvec) * inv_det;
  if (!(u >= -kEdgeTolerance && u <= 1.0 + kEdgeTolerance)) return false;
  const Vec3 qvec = tvec.cross(e1);
  double v = d.dot(qvec) * inv_det;
  if (!(v >= -kEdgeTolerance && u + v <= 1.0 + kEdgeTolerance)) return false;
  u = std::clamp(u, 0.0, 1.0);
  v = std::clamp(v, 0.0, 1.0 - u);
  const double t = e2.dot(qvec) * inv_det;
  if (!(t >= 0.0 && t <= 1.0)) return false;
  // Degeneracy last: a zero-area triangle usually fails above (det = 0), and most triangles
  // are rejected before this point.
  Vec3 n_raw;
  if (degenerate_with_normal(p0, p1, p2, n_raw)) return false;
  const Vec3 n = n_raw.normalized();
  contact.t = t;
  contact.point = p0 + u * e1 + v * e2;
  contact.barycentric = Vec3(1.0 - u - v, u, v);
  contact.normal = front ? n : Vec3(-n);
  contact.front = front;
  return true;
}

bool sweep_sphere_triangle(const Vec3& a, const Vec3& d, double radius, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                           TouchableFace face, TriangleContact& contact) {
  if (!(radius >= 0.0)) return false;
  const double r2 = radius * radius;

  // Where the sphere starts. Beyond radius + |d| it cannot reach the triangle (the common
  // case, tested before anything else; NaN from a degenerate triangle fails it too);
  // overlapping, it touches now if it approaches, and never otherwise (the distance is
  // convex in t).
  Vec3 barycentric;
  const Vec3 q0 = closest_point_on_triangle(a, p0, p1, p2, barycentric);
  const Vec3 gap0 = a - q0;
  const double dist2 = gap0.squaredNorm();
  const double reach = radius + d.norm();
  if (!(dist2 <= reach * reach)) return false;
  Vec3 n_raw;
  if (degenerate_with_normal(p0, p1, p2, n_raw)) return false;
  const Vec3 n = n_raw.normalized();
  if (dist2 < r2) {
    return finish_sphere_contact(0.0, q0, barycentric, contact_normal(gap0, n, d), n, d, face, contact);
  }

  // Face: the signed plane distance s(t) = s0 + t·sd reaches ±radius with the touching point
  // c(t) ∓ radius·n inside the triangle. Such a contact is necessarily the first one (before
  // it the plane distance, a lower bound of the distance, exceeds the radius).
  const double s0 = (a - p0).dot(n);
  const double sd = d.dot(n);
  if ((sd < 0.0 && s0 >= radius) || (sd > 0.0 && s0 <= -radius)) {
    const double side = sd < 0.0 ? 1.0 : -1.0;
    const double t = (s0 - side * radius) / (-sd);
    if (t <= 1.0) {
      const Vec3 q = a + t * d - side * radius * n;
      Vec3 w;
      if (inside_triangle(q, p0, p1, p2, n_raw, w)) {
        return finish_sphere_contact(t, q, w, side * n, n, d, face, contact);
      }
    }
  }

  // Edges: entry of the centre's line into the infinite cylinder of the edge, Ericson §5.3.7.
  // With e = Q − P and w = a − P, |(w + t·d) × e|² = radius²·|e|² is A·t² + 2B·t + C = 0 with
  // A = |d×e|², B = (w×e)·(d×e), C = |w×e|² − radius²·|e|²; the smaller root in the stable
  // form t = C / (−B + √(B² − A·C)) needs B < 0 (approaching the line). The contact must
  // project inside the edge, otherwise the vertex spheres below catch it.
  const Vec3* vertex[3] = {&p0, &p1, &p2};
  double best_t = std::numeric_limits<double>::infinity();
  Vec3 best_point = Vec3::Zero();
  Vec3 best_weights = Vec3::Zero();
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const Vec3& p = *vertex[i];
    const Vec3 e = *vertex[j] - p;
    const double e2 = e.squaredNorm();
    const Vec3 wxe = (a - p).cross(e);
    const Vec3 dxe = d.cross(e);
    const double qa = dxe.squaredNorm();
    const double qb = wxe.dot(dxe);
    const double qc = wxe.squaredNorm() - r2 * e2;
    if (!(qa > 0.0 && qb < 0.0)) continue;
    const double disc = qb * qb - qa * qc;
    if (!(disc >= 0.0)) continue;
    const double t = qc / (-qb + std::sqrt(disc));
    if (!(t >= 0.0 && t <= 1.0 && t < best_t)) continue;
    const double s = (a + t * d - p).dot(e) / e2;
    if (!(s >= 0.0 && s <= 1.0)) continue;
    best_t = t;
    best_point = p + s * e;
    best_weights = Vec3::Zero();
    best_weights[i] = 1.0 - s;
    best_weights[j] = s;
  }

  // Vertices: |w + t·d|² = radius² with w = a − V (Ericson §5.3.2), same stable root.
  const double dd = d.squaredNorm();
  for (int i = 0; i < 3; ++i) {
    const Vec3 w = a - *vertex[i];
    const double qb = w.dot(d);
    const double qc = w.squaredNorm() - r2;
    if (!(qb < 0.0)) continue;
    const double disc = qb * qb - dd * qc;
    if (!(disc >= 0.0)) continue;
    const double t = qc / (-qb + std::sqrt(disc));
    if (!(t >= 0.0 && t <= 1.0 && t < best_t)) continue;
    best_t = t;
    best_point = *vertex[i];
    best_weights = Vec3::Zero();
    best_weights[i] = 1.0;
  }

  if (!(best_t <= 1.0)) return false;
  const Vec3 m = contact_normal(a + best_t * d - best_point, n, d);
  return finish_sphere_contact(best_t, best_point, best_weights, m, n, d, face, contact);
}

// Ericson §5.1.9. With d1 = p1 − p0, d2 = q1 − q0, r = p0 − q0 the squared distance
// |r + s·d1 − t·d2|² is minimised by a·s − b·t = −c, b·s − e·t = −f (a = d1·d1, b = d1·d2,
// c = d1·r, e = d2·d2, f = d2·r). Clamp s to [0, 1], take the t that is best for it, and if
// that t must be clamped, recompute s for the clamped t (the distance is convex in (s, t)).
SegmentClosest closest_points_segment_segment(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0;
  const Vec3 d2 = q1 - q0;
  const Vec3 r = p0 - q0;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  const auto clamp01 = [](double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); };
  double s = 0.0;
  double t = 0.0;
  if (a > 0.0 && e > 0.0) {
    const double b = d1.dot(d2);
    const double c = d1.dot(r);
    const double denom = a * e - b * b;  // = |d1×d2|² ≥ 0
    s = denom > 1e-12 * a * e ? clamp01((b * f - c * e) / denom) : 0.0;
    t = (b * s + f) / e;
    if (t < 0.0) {
      t = 0.0;
      s = clamp01(-c / a);
    } else if (t > 1.0) {
      t = 1.0;
      s = clamp01((b - c) / a);
    }
  } else if (e > 0.0) {  // p is a point
    t = clamp01(f / e);
  } else if (a > 0.0) {  // q is a point
    s = clamp01(-d1.dot(r) / a);
  }
  SegmentClosest out;
  out.s = s;
  out.t = t;
  out.on_p = p0 + s * d1;
  out.on_q = q0 + t * d2;
  out.distance_squared = (out.on_p - out.on_q).squaredNorm();
  return out;
}

}  // namespace hof::collision::detail

namespace hof::collision {

double point_triangle_distance_squared(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  Vec3 barycentric;
  return (detail::closest_point_on_triangle(p, p0, p1, p2, barycentric) - p).squaredNorm();
}

}  // namespace hof::collision
