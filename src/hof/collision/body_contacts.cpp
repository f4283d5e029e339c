// Contact detection between bodies, after SOFA's pipeline (BruteForceBroadPhase: every pair of
// bodies by their boxes; BVHNarrowPhase: each body's AABB tree; MinProximityIntersection /
// LocalMinDistance: the closest primitive pairs within the alarm distance). Per pass: refit
// the trees, box each body, then for each pair query the other body's tree with each vertex
// (closest point), each edge (the triangles whose boxes overlap the edge's box, then their
// edges) and each sphere. Geometry: Ericson, Real-Time Collision Detection (2005), §5.1.5
// (point–triangle) and §5.1.9 (segment–segment), in triangle_queries.cpp.

#include "hof/collision/body_contacts.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hof/collision/triangle_queries.h"

namespace hof::collision {
namespace {

constexpr double kNoContact = std::numeric_limits<double>::infinity();

const Vec3& triangle_corner(const TriangleMeshView& mesh, std::int32_t triangle, int k) {
  return mesh.vertices[static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(triangle)][k])];
}

// Unit front normal (b−a)×(c−a); zero for a degenerate triangle (the queries never return
// one, but an edge may border one).
Vec3 face_normal(const TriangleMeshView& mesh, std::int32_t triangle) {
  const Vec3& a = triangle_corner(mesh, triangle, 0);
  const Vec3 n = (triangle_corner(mesh, triangle, 1) - a).cross(triangle_corner(mesh, triangle, 2) - a);
  const double length = n.norm();
  return length > 0.0 ? Vec3(n / length) : Vec3(Vec3::Zero());
}

bool all_finite(std::span<const Vec3> points) {
  return std::all_of(points.begin(), points.end(), [](const Vec3& p) { return p.allFinite(); });
}

ContactPoint vertex_point(std::int32_t body, std::int32_t vertex, const Vec3& p) {
  ContactPoint c;
  c.body = body;
  c.kind = PrimitiveKind::kVertex;
  c.vertices = {vertex, -1, -1};
  c.weights = {1.0, 0.0, 0.0};
  c.point = p;
  return c;
}

ContactPoint sphere_point(std::int32_t body, std::int32_t sphere, const Vec3& p) {
  ContactPoint c = vertex_point(body, sphere, p);
  c.kind = PrimitiveKind::kSphere;
  return c;
}

ContactPoint triangle_point(std::int32_t body, const TriangleMeshView& mesh, std::int32_t triangle,
                            const Vec3& barycentric, const Vec3& q) {
  ContactPoint c;
  c.body = body;
  c.kind = PrimitiveKind::kTriangle;
  const mesh::Tri& t = mesh.triangles[static_cast<std::size_t>(triangle)];
  c.vertices = {t[0], t[1], t[2]};
  c.weights = {barycentric[0], barycentric[1], barycentric[2]};
  c.point = q;
  return c;
}

// Signed gap and normal of a point p (a vertex or sphere centre) against its closest point q
// (barycentric weights w) on a triangle with corner `a` and unit front normal n: in front (or
// on the plane) the gap is |p − q| and the normal points from q to p; behind it the gap is
// −|p − q| and the normal points from p to q (the way out). When q is inside the face both
// are n, and the plane distance (p − a)·n is the gap: more accurate than
// normalising p − q, which has the rounding of q's coordinates. A p within rounding of q
// (on an edge or corner) gets the face normal and gap 0.
void signed_gap(const Vec3& p, const Vec3& q, const Vec3& w, const Vec3& a, const Vec3& n, double& distance,
                Vec3& normal) {
  const double plane = (p - a).dot(n);
  const bool front = plane >= 0.0;
  if (w.minCoeff() > 0.0) {
    normal = n;  // q → p in front, p → q (the way out) behind: both along n
    distance = plane;
    return;
  }
  const Vec3 gap = p - q;
  const double length = gap.norm();
  const double rounding = 64.0 * std::numeric_limits<double>::epsilon() * std::fmax(p.cwiseAbs().maxCoeff(), 1e-300);
  if (length > rounding) {
    normal = front ? Vec3(gap / length) : Vec3(-gap / length);
    distance = front ? length : -length;
  } else {
    normal = n;
    distance = 0.0;
  }
}

// Whether a closest point lies on a boundary edge of an open surface: a zero weight puts it
// on the edge opposite that corner (edge k of a triangle joins corners k and k + 1), and a
// boundary edge has one adjacent triangle.
template <class State>
bool on_rim(const State& st, const ClosestPoint& cp) {
  for (int k = 0; k < 3; ++k) {
    if (cp.barycentric[k] > 0.0) continue;
    const std::int32_t e =
        st.triangle_edges[static_cast<std::size_t>(cp.triangle)][static_cast<std::size_t>((k + 1) % 3)];
    if (e >= 0 && st.edge_triangles[static_cast<std::size_t>(e)][1] < 0) return true;
  }
  return false;
}

}  // namespace

void ContactDetector::reset(std::span<const CollisionBody> bodies, const AabbTreeOptions& tree) {
  const std::size_t n = bodies.size();
  trees_.clear();
  trees_.reserve(n);
  states_.assign(n, BodyState{});
  for (std::size_t i = 0; i < n; ++i) {
    const TriangleMeshView& surface = bodies[i].surface;
    BodyState& st = states_[i];
    st.vertex_count = surface.vertices.size();
    st.triangle_count = surface.triangles.size();
    const auto v_count = static_cast<std::int64_t>(st.vertex_count);
    st.valid_topology = st.vertex_count < static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) &&
                        st.triangle_count < static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) &&
                        std::all_of(surface.triangles.begin(), surface.triangles.end(), [&](const mesh::Tri& t) {
                          return std::all_of(t.begin(), t.end(), [&](std::int32_t v) { return v >= 0 && v < v_count; });
                        });
    if (!st.valid_topology) {
      trees_.emplace_back();
      continue;
    }
    trees_.push_back(AabbTree::build(surface, tree));
    const auto f_count = static_cast<std::int32_t>(st.triangle_count);

    // Unique edges: every (lower, higher, triangle, corner) sorted, then grouped.
    std::vector<std::array<std::int32_t, 4>> sides;
    sides.reserve(3 * st.triangle_count);
    for (std::int32_t t = 0; t < f_count; ++t) {
      const mesh::Tri& tri = surface.triangles[static_cast<std::size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = tri[k];
        const std::int32_t b = tri[(k + 1) % 3];
        if (a != b) sides.push_back({std::min(a, b), std::max(a, b), t, k});
      }
    }
    std::sort(sides.begin(), sides.end());
    st.triangle_edges.assign(st.triangle_count, {-1, -1, -1});
    for (std::size_t k = 0; k < sides.size();) {
      const auto e = static_cast<std::int32_t>(st.edges.size());
      st.edges.push_back({sides[k][0], sides[k][1]});
      st.edge_triangles.push_back({sides[k][2], -1});
      std::size_t m = k;
      for (; m < sides.size() && sides[m][0] == sides[k][0] && sides[m][1] == sides[k][1]; ++m) {
        st.triangle_edges[static_cast<std::size_t>(sides[m][2])][static_cast<std::size_t>(sides[m][3])] = e;
        if (m == k + 1) st.edge_triangles.back()[1] = sides[m][2];
      }
      k = m;
    }

    // Self-collision skip lists: the triangles around each vertex and their edge neighbours.
    std::vector<std::int32_t> ring_offsets(st.vertex_count + 1, 0);
    for (const mesh::Tri& tri : surface.triangles) {
      for (int k = 0; k < 3; ++k) ++ring_offsets[static_cast<std::size_t>(tri[k]) + 1];
    }
    for (std::size_t v = 0; v < st.vertex_count; ++v) ring_offsets[v + 1] += ring_offsets[v];
    std::vector<std::int32_t> ring(static_cast<std::size_t>(ring_offsets.back()));
    std::vector<std::int32_t> fill(ring_offsets.begin(), ring_offsets.end() - 1);
    for (std::int32_t t = 0; t < f_count; ++t) {
      for (int k = 0; k < 3; ++k) {
        ring[static_cast<std::size_t>(fill[static_cast<std::size_t>(surface.triangles[t][k])]++)] = t;
      }
    }
    st.skip_offsets.assign(st.vertex_count + 1, 0);
    std::vector<std::int32_t> list;
    for (std::size_t v = 0; v < st.vertex_count; ++v) {
      list.clear();
      for (std::int32_t r = ring_offsets[v]; r < ring_offsets[v + 1]; ++r) {
        const std::int32_t t = ring[static_cast<std::size_t>(r)];
        list.push_back(t);
        for (const std::int32_t e : st.triangle_edges[static_cast<std::size_t>(t)]) {
          if (e < 0) continue;
          for (const std::int32_t u : st.edge_triangles[static_cast<std::size_t>(e)]) {
            if (u >= 0) list.push_back(u);
          }
        }
      }
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      st.skip_triangles.insert(st.skip_triangles.end(), list.begin(), list.end());
      st.skip_offsets[v + 1] = static_cast<std::int32_t>(st.skip_triangles.size());
    }
    st.inside.assign(st.vertex_count * n, -1);
    st.inside_count.assign(n, 0);
  }
}

void ContactDetector::detect(std::span<const CollisionBody> bodies, const DetectionSettings& settings,
                             std::vector<BodyContact>& contacts) {
  contacts.clear();
  const std::size_t n = bodies.size();
  if (n != states_.size()) return;
  const double alarm =
      std::isfinite(settings.alarm_distance_m) && settings.alarm_distance_m > 0.0 ? settings.alarm_distance_m : 0.0;

  for (std::size_t i = 0; i < n; ++i) {
    const CollisionBody& body = bodies[i];
    BodyState& st = states_[i];
    st.active = st.valid_topology && body.surface.vertices.size() == st.vertex_count &&
                body.surface.triangles.size() == st.triangle_count && all_finite(body.surface.vertices);
    st.use_previous = body.previous_vertices.size() == st.vertex_count && all_finite(body.previous_vertices);
    st.sphere_count = body.sphere_centers.size() == body.sphere_radii.size() ? body.sphere_centers.size() : 0;
    if (!st.active) continue;
    if (body.moving && trees_[i].refit(body.surface)) {
      trees_[i] = AabbTree::build(body.surface, trees_[i].options());  // the boxes had grown too loose
    }
    Vec3 lo = Vec3::Constant(kNoContact);
    Vec3 hi = Vec3::Constant(-kNoContact);
    for (const Vec3& p : body.surface.vertices) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    if (st.use_previous) {  // the swept box: continuous detection looks along the motion
      for (const Vec3& p : body.previous_vertices) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
    for (std::size_t s = 0; s < st.sphere_count; ++s) {
      const double r = body.sphere_radii[s];
      const Vec3& c = body.sphere_centers[s];
      if (!(r >= 0.0 && std::isfinite(r) && c.allFinite())) continue;
      lo = lo.cwiseMin(c - Vec3::Constant(r));
      hi = hi.cwiseMax(c + Vec3::Constant(r));
    }
    st.lo = lo;
    st.hi = hi;
  }

  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i; j < n; ++j) {
      const CollisionBody& bi = bodies[i];
      const CollisionBody& bj = bodies[j];
      const BodyState& si = states_[i];
      const BodyState& sj = states_[j];
      if (!si.active || !sj.active) continue;
      if (i == j && !bi.self_collision) continue;
      if (!bi.simulated && !bj.simulated) continue;
      if (i != j && bi.group >= 0 && bi.group == bj.group) continue;
      // Broad phase: the bodies' boxes, one inflated by the alarm distance (an empty box,
      // lo > hi, overlaps nothing); a pair with vertices known to be inside the other body
      // is tested whatever its boxes (a vertex under an open floor is outside its box).
      const bool remembered = i != j && (si.inside_count[j] > 0 || sj.inside_count[i] > 0);
      if (!remembered &&
          !((si.lo.array() - alarm <= sj.hi.array()).all() && (sj.lo.array() <= si.hi.array() + alarm).all())) {
        continue;
      }
      const auto ia = static_cast<std::int32_t>(i);
      const auto ib = static_cast<std::int32_t>(j);
      if (bi.points && bj.triangles) points_against_triangles(bodies, ia, ib, alarm, contacts);
      if (i != j && bj.points && bi.triangles) points_against_triangles(bodies, ib, ia, alarm, contacts);
      if (bi.lines && bj.lines) edges_against_edges(bodies, ia, ib, alarm, contacts);
      if (i != j) {
        if (bj.triangles) spheres_against_triangles(bodies, ia, ib, alarm, contacts);
        if (bi.triangles) spheres_against_triangles(bodies, ib, ia, alarm, contacts);
        spheres_against_spheres(bodies, ia, ib, alarm, contacts);
      }
    }
  }
}

void ContactDetector::points_against_triangles(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib,
                                               double alarm, std::vector<BodyContact>& contacts) {
  const CollisionBody& a = bodies[static_cast<std::size_t>(ia)];
  const CollisionBody& b = bodies[static_cast<std::size_t>(ib)];
  BodyState& sa = states_[static_cast<std::size_t>(ia)];
  const AabbTree& tree = trees_[static_cast<std::size_t>(ib)];
  const bool self = ia == ib;
  const std::size_t n = bodies.size();
  // Only what comes near b's box needs a tree query (most of a body is far from the other).
  const BodyState& sb = states_[static_cast<std::size_t>(ib)];
  const Vec3 zone_lo = sb.lo - Vec3::Constant(alarm);
  const Vec3 zone_hi = sb.hi + Vec3::Constant(alarm);
  const auto near_zone = [&](const Vec3& lo, const Vec3& hi) {
    return (lo.array() <= zone_hi.array()).all() && (zone_lo.array() <= hi.array()).all();
  };

  const auto emit = [&](std::int32_t v, const Vec3& p, std::int32_t triangle, const Vec3& barycentric, const Vec3& q,
                        const Vec3& normal, double distance) {
    BodyContact c;
    c.a = vertex_point(ia, v, p);
    c.b = triangle_point(ib, b.surface, triangle, barycentric, q);
    c.normal = normal;
    c.distance = distance;
    contacts.push_back(c);
  };

  for (std::size_t v = 0; v < sa.vertex_count; ++v) {
    const Vec3& p = a.surface.vertices[v];
    const auto vi = static_cast<std::int32_t>(v);
    if (!self) {
      std::int32_t& known = sa.inside[v * n + static_cast<std::size_t>(ib)];
      std::int32_t& count = sa.inside_count[static_cast<std::size_t>(ib)];
      // Continuous: the motion since the previous pass entered b through a front face.
      if (sa.use_previous && near_zone(a.previous_vertices[v].cwiseMin(p), a.previous_vertices[v].cwiseMax(p))) {
        const SweepHit hit = tree.first_hit_segment(b.surface, a.previous_vertices[v], p, TouchableFace::kFront);
        if (hit.triangle >= 0) {
          const Vec3 normal = face_normal(b.surface, hit.triangle);
          const double depth = (p - triangle_corner(b.surface, hit.triangle, 0)).dot(normal);
          if (depth < 0.0) {
            Vec3 weights;
            const Vec3 q = detail::closest_point_on_triangle(p, triangle_corner(b.surface, hit.triangle, 0),
                                                             triangle_corner(b.surface, hit.triangle, 1),
                                                             triangle_corner(b.surface, hit.triangle, 2), weights);
            emit(vi, p, hit.triangle, weights, q, normal, depth);
            if (known < 0) ++count;
            known = hit.triangle;
            continue;
          }
        }
      }
      // Known to be inside: still reported while its nearest surface point is in front of it
      // (not on an open surface's rim: a vertex that slid off a floor's edge is free).
      if (known >= 0) {
        const ClosestPoint cp = tree.closest_point(b.surface, p, kNoContact, TouchableFace::kFrontAndBack);
        if (cp.triangle >= 0 && !on_rim(sb, cp)) {
          double distance = 0.0;
          Vec3 normal;
          signed_gap(p, cp.point, cp.barycentric, triangle_corner(b.surface, cp.triangle, 0),
                     face_normal(b.surface, cp.triangle), distance, normal);
          if (distance < 0.0) {
            emit(vi, p, cp.triangle, cp.barycentric, cp.point, normal, distance);
            known = cp.triangle;
            continue;
          }
        }
        known = -1;
        --count;
      }
    }
    if (!near_zone(p, p)) continue;
    const std::span<const std::int32_t> skip =
        self ? std::span<const std::int32_t>(sa.skip_triangles)
                   .subspan(static_cast<std::size_t>(sa.skip_offsets[v]),
                            static_cast<std::size_t>(sa.skip_offsets[v + 1] - sa.skip_offsets[v]))
             : std::span<const std::int32_t>{};
    const ClosestPoint cp = tree.closest_point(b.surface, p, alarm, TouchableFace::kFrontAndBack, skip);
    if (cp.triangle < 0) continue;
    double distance = 0.0;
    Vec3 normal;
    signed_gap(p, cp.point, cp.barycentric, triangle_corner(b.surface, cp.triangle, 0),
               face_normal(b.surface, cp.triangle), distance, normal);
    emit(vi, p, cp.triangle, cp.barycentric, cp.point, normal, distance);
  }
}

void ContactDetector::edges_against_edges(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib,
                                          double alarm, std::vector<BodyContact>& contacts) const {
  const CollisionBody& a = bodies[static_cast<std::size_t>(ia)];
  const CollisionBody& b = bodies[static_cast<std::size_t>(ib)];
  const BodyState& sa = states_[static_cast<std::size_t>(ia)];
  const BodyState& sb = states_[static_cast<std::size_t>(ib)];
  const AabbTree& tree = trees_[static_cast<std::size_t>(ib)];
  const bool self = ia == ib;
  const double alarm2 = alarm * alarm;
  const Vec3 zone_lo = sb.lo - Vec3::Constant(alarm);
  const Vec3 zone_hi = sb.hi + Vec3::Constant(alarm);

  // Outward direction of an edge: the sum of its adjacent triangles' unit normals.
  const auto edge_normal = [](const CollisionBody& body, const BodyState& st, std::int32_t e) {
    Vec3 sum = Vec3::Zero();
    for (const std::int32_t t : st.edge_triangles[static_cast<std::size_t>(e)]) {
      if (t >= 0) sum += face_normal(body.surface, t);
    }
    return sum;
  };
  const auto in_skip = [&](std::int32_t vertex, std::int32_t triangle) {
    const auto first = sa.skip_triangles.begin() + sa.skip_offsets[static_cast<std::size_t>(vertex)];
    const auto last = sa.skip_triangles.begin() + sa.skip_offsets[static_cast<std::size_t>(vertex) + 1];
    return std::binary_search(first, last, triangle);
  };

  for (std::size_t e = 0; e < sa.edges.size(); ++e) {
    const auto ei = static_cast<std::int32_t>(e);
    const std::array<std::int32_t, 2>& ea = sa.edges[e];
    const Vec3& p0 = a.surface.vertices[static_cast<std::size_t>(ea[0])];
    const Vec3& p1 = a.surface.vertices[static_cast<std::size_t>(ea[1])];
    const Vec3 lo = p0.cwiseMin(p1);
    const Vec3 hi = p0.cwiseMax(p1);
    if (!((lo.array() <= zone_hi.array()).all() && (zone_lo.array() <= hi.array()).all())) continue;
    const std::size_t begin = contacts.size();
    tree.visit_overlapping(lo, hi, alarm, [&](std::int32_t t) {
      for (const std::int32_t f : sb.triangle_edges[static_cast<std::size_t>(t)]) {
        // Each edge once: from its owner (lowest-index adjacent triangle), whose box holds it.
        if (f < 0 || sb.edge_triangles[static_cast<std::size_t>(f)][0] != t) continue;
        const std::array<std::int32_t, 2>& eb = sb.edges[static_cast<std::size_t>(f)];
        if (self) {
          if (f <= ei || eb[0] == ea[0] || eb[0] == ea[1] || eb[1] == ea[0] || eb[1] == ea[1]) continue;
          bool adjacent = false;
          for (const std::int32_t u : sb.edge_triangles[static_cast<std::size_t>(f)]) {
            if (u >= 0 && (in_skip(ea[0], u) || in_skip(ea[1], u))) adjacent = true;
          }
          if (adjacent) continue;
        }
        const Vec3& q0 = b.surface.vertices[static_cast<std::size_t>(eb[0])];
        const Vec3& q1 = b.surface.vertices[static_cast<std::size_t>(eb[1])];
        const detail::SegmentClosest sc = detail::closest_points_segment_segment(p0, p1, q0, q1);
        // Interior on both edges: a closest point at an endpoint is a vertex's contact.
        if (!(sc.distance_squared <= alarm2) || !(sc.s > 0.0 && sc.s < 1.0 && sc.t > 0.0 && sc.t < 1.0)) continue;
        const Vec3 d1 = p1 - p0;
        const Vec3 d2 = q1 - q0;
        Vec3 normal = d1.cross(d2);
        const double length2 = normal.squaredNorm();
        // Interior closest points of non-parallel segments are joined along d1×d2; nearly
        // parallel edges have no unique pair (Ericson's clamp puts s at an endpoint anyway).
        if (!(length2 > 1e-12 * d1.squaredNorm() * d2.squaredNorm())) continue;
        normal /= std::sqrt(length2);
        // a is outside b when the gap points along b's outward normal and against a's.
        const Vec3 reference = edge_normal(b, sb, f) - edge_normal(a, sa, ei);
        const Vec3 gap = sc.on_p - sc.on_q;
        const double orientation = normal.dot(reference);
        if (orientation < 0.0 || (orientation == 0.0 && normal.dot(gap) < 0.0)) normal = -normal;
        BodyContact c;
        c.a.body = ia;
        c.a.kind = PrimitiveKind::kEdge;
        c.a.vertices = {ea[0], ea[1], -1};
        c.a.weights = {1.0 - sc.s, sc.s, 0.0};
        c.a.point = sc.on_p;
        c.b.body = ib;
        c.b.kind = PrimitiveKind::kEdge;
        c.b.vertices = {eb[0], eb[1], -1};
        c.b.weights = {1.0 - sc.t, sc.t, 0.0};
        c.b.point = sc.on_q;
        c.normal = normal;
        c.distance = normal.dot(gap);
        contacts.push_back(c);
      }
    });
    // The tree's visiting order depends on its layout (rebuilds): sort by b's edge so the
    // output depends only on the input.
    std::sort(contacts.begin() + static_cast<std::ptrdiff_t>(begin), contacts.end(),
              [](const BodyContact& x, const BodyContact& y) { return x.b.vertices < y.b.vertices; });
  }
}

void ContactDetector::spheres_against_triangles(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib,
                                                double alarm, std::vector<BodyContact>& contacts) const {
  const CollisionBody& a = bodies[static_cast<std::size_t>(ia)];
  const CollisionBody& b = bodies[static_cast<std::size_t>(ib)];
  const BodyState& sa = states_[static_cast<std::size_t>(ia)];
  const AabbTree& tree = trees_[static_cast<std::size_t>(ib)];
  for (std::size_t s = 0; s < sa.sphere_count; ++s) {
    const Vec3& center = a.sphere_centers[s];
    const double radius = a.sphere_radii[s];
    if (!(radius >= 0.0 && std::isfinite(radius) && center.allFinite())) continue;
    const ClosestPoint cp = tree.closest_point(b.surface, center, alarm + radius, TouchableFace::kFrontAndBack);
    if (cp.triangle < 0) continue;
    double gap = 0.0;
    Vec3 normal;
    signed_gap(center, cp.point, cp.barycentric, triangle_corner(b.surface, cp.triangle, 0),
               face_normal(b.surface, cp.triangle), gap, normal);
    BodyContact c;
    c.a = sphere_point(ia, static_cast<std::int32_t>(s), center - radius * normal);
    c.b = triangle_point(ib, b.surface, cp.triangle, cp.barycentric, cp.point);
    c.normal = normal;
    c.distance = gap - radius;
    contacts.push_back(c);
  }
}

void ContactDetector::spheres_against_spheres(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib,
                                              double alarm, std::vector<BodyContact>& contacts) const {
  const CollisionBody& a = bodies[static_cast<std::size_t>(ia)];
  const CollisionBody& b = bodies[static_cast<std::size_t>(ib)];
  const BodyState& sa = states_[static_cast<std::size_t>(ia)];
  const BodyState& sb = states_[static_cast<std::size_t>(ib)];
  for (std::size_t s = 0; s < sa.sphere_count; ++s) {
    const Vec3& ca = a.sphere_centers[s];
    const double ra = a.sphere_radii[s];
    if (!(ra >= 0.0 && std::isfinite(ra) && ca.allFinite())) continue;
    for (std::size_t u = 0; u < sb.sphere_count; ++u) {
      const Vec3& cb = b.sphere_centers[u];
      const double rb = b.sphere_radii[u];
      if (!(rb >= 0.0 && std::isfinite(rb) && cb.allFinite())) continue;
      const Vec3 w = ca - cb;
      const double reach = ra + rb + alarm;
      if (!(w.squaredNorm() <= reach * reach)) continue;
      const double length = w.norm();
      const Vec3 normal = length > 0.0 ? Vec3(w / length) : Vec3(Vec3::UnitZ());  // coincident: any direction
      BodyContact c;
      c.a = sphere_point(ia, static_cast<std::int32_t>(s), ca - ra * normal);
      c.b = sphere_point(ib, static_cast<std::int32_t>(u), cb + rb * normal);
      c.normal = normal;
      c.distance = length - ra - rb;
      contacts.push_back(c);
    }
  }
}

}  // namespace hof::collision
