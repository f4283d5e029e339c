#include "hof/procedures/shaped_tool.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/surface_check.h"

namespace hof::procedures {

namespace {

// The time constant of the proxy velocity's low-pass filter: about one simulation step (the
// rate at which the surfaces under the proxy move), s.
constexpr double kProxyVelocityTimeConstant_s = 0.01;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Closest points of segments p1–q1 and p2–q2 (Ericson §5.1.9): parameters s, t in [0, 1].
void closest_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, double& s, double& t) {
  const Vec3 d1 = q1 - p1;
  const Vec3 d2 = q2 - p2;
  const Vec3 r = p1 - p2;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  constexpr double kTiny = 1e-300;
  if (a <= kTiny && e <= kTiny) {
    s = t = 0.0;
    return;
  }
  if (a <= kTiny) {
    s = 0.0;
    t = std::clamp(f / e, 0.0, 1.0);
    return;
  }
  const double c = d1.dot(r);
  if (e <= kTiny) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
    return;
  }
  const double b = d1.dot(d2);
  const double denom = a * e - b * b;  // ≥ 0; 0 when parallel: any s, take 0
  s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

// Closest point of triangle (p0, p1, p2) to p (Ericson §5.1.5, Voronoi regions), with its
// barycentric weights.
Vec3 closest_point_triangle(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2, Vec3& w) {
  const Vec3 ab = p1 - p0;
  const Vec3 ac = p2 - p0;
  const Vec3 ap = p - p0;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    w = Vec3(1, 0, 0);
    return p0;
  }
  const Vec3 bp = p - p1;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    w = Vec3(0, 1, 0);
    return p1;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    w = Vec3(1.0 - v, v, 0.0);
    return p0 + v * ab;
  }
  const Vec3 cp = p - p2;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    w = Vec3(0, 0, 1);
    return p2;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double v = d2 / (d2 - d6);
    w = Vec3(1.0 - v, 0.0, v);
    return p0 + v * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w = Vec3(0.0, 1.0 - v, v);
    return p1 + v * (p2 - p1);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom;
  const double u = vc * denom;
  w = Vec3(1.0 - v - u, v, u);
  return p0 + v * ab + u * ac;
}

// The triangle's bounding sphere (centroid, farthest vertex): a cheap rejection.
void bounding_sphere(const Vec3& p0, const Vec3& p1, const Vec3& p2, Vec3& centre, double& radius) {
  centre = (p0 + p1 + p2) / 3.0;
  radius = std::sqrt(std::max({(p0 - centre).squaredNorm(), (p1 - centre).squaredNorm(), (p2 - centre).squaredNorm()}));
}

// Distance from point p to segment a–b.
double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double dd = d.squaredNorm();
  const double t = dd > 0.0 ? std::clamp((p - a).dot(d) / dd, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

}  // namespace

std::string_view shape_name(ToolShape shape) {
  switch (shape) {
    case ToolShape::kSphere:
      return "sphere";
    case ToolShape::kCapsule:
      return "capsule";
    case ToolShape::kMesh:
      return "mesh";
  }
  return "sphere";
}

double closest_segment_triangle(const Vec3& a, const Vec3& b, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                Vec3& on_segment, Vec3& on_triangle, Vec3& barycentric) {
  const Vec3 n = (p1 - p0).cross(p2 - p0);
  const double longest = std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
  if (!(n.norm() > 1e-12 * longest)) return kInfinity;  // degenerate (or non-finite)
  // The segment crossing the triangle: distance 0 there.
  const double da = (a - p0).dot(n);
  const double db = (b - p0).dot(n);
  if ((da <= 0.0 && db >= 0.0) || (da >= 0.0 && db <= 0.0)) {
    if (da != db) {
      const Vec3 q = a + (da / (da - db)) * (b - a);
      Vec3 w;
      const Vec3 c = closest_point_triangle(q, p0, p1, p2, w);
      if ((c - q).squaredNorm() <= 1e-24 * longest) {
        on_segment = on_triangle = c;
        barycentric = w;
        return 0.0;
      }
    }
  }
  // Otherwise the closest pair has an endpoint of the segment or a point of an edge.
  double best = kInfinity;
  const auto consider = [&](const Vec3& s, const Vec3& t, const Vec3& w) {
    const double d = (s - t).squaredNorm();
    if (d < best) {
      best = d;
      on_segment = s;
      on_triangle = t;
      barycentric = w;
    }
  };
  Vec3 w;
  Vec3 c = closest_point_triangle(a, p0, p1, p2, w);
  consider(a, c, w);
  if ((b - a).squaredNorm() > 0.0) {
    c = closest_point_triangle(b, p0, p1, p2, w);
    consider(b, c, w);
    const std::array<const Vec3*, 3> v{&p0, &p1, &p2};
    for (int e = 0; e < 3; ++e) {
      const Vec3& u0 = *v[static_cast<std::size_t>(e)];
      const Vec3& u1 = *v[static_cast<std::size_t>((e + 1) % 3)];
      double s = 0.0;
      double t = 0.0;
      closest_segment_segment(a, b, u0, u1, s, t);
      Vec3 we = Vec3::Zero();
      we[e] = 1.0 - t;
      we[(e + 1) % 3] = t;
      consider(a + s * (b - a), u0 + t * (u1 - u0), we);
    }
  }
  return std::sqrt(best);
}

Expected<void> validate(const ShapedToolConfig& c) {
  const auto fail = [](std::string message) -> Expected<void> {
    return make_error(ErrorCode::kInvalidArgument, std::move(message));
  };
  if (!std::isfinite(c.radius_m) || c.radius_m < 0.0 || (c.shape != ToolShape::kMesh && c.radius_m == 0.0)) {
    return fail(fmt::format("<tool> radius must be a positive number of metres{}, got {}",
                            c.shape == ToolShape::kMesh ? " (or 0: chosen from the mesh)" : "", c.radius_m));
  }
  if (!std::isfinite(c.length_m) || c.length_m < 0.0) {
    return fail(fmt::format("<tool> length must be a number of metres ≥ 0, got {}", c.length_m));
  }
  const Vec3 axis(c.orientation[0], c.orientation[1], c.orientation[2]);
  if (!axis.allFinite() || !std::isfinite(c.orientation[3]) || (axis.norm() == 0.0 && c.orientation[3] != 0.0)) {
    return fail("<tool> orientation must be an axis (not zero) and an angle in radians, \"x y z angle\"");
  }
  if (!std::isfinite(c.stiffness_n_per_m) || c.stiffness_n_per_m < 0.0) {
    return fail(fmt::format("<tool> stiffness must be ≥ 0 N/m (0: the device's), got {}", c.stiffness_n_per_m));
  }
  if (!std::isfinite(c.damping_n_s_per_m) || c.damping_n_s_per_m < 0.0) {
    return fail(fmt::format("<tool> damping must be ≥ 0 N·s/m, got {}", c.damping_n_s_per_m));
  }
  if (c.shape == ToolShape::kMesh && c.mesh.empty()) return fail("<tool shape=\"mesh\"> needs mesh=\"FILE\"");
  return {};
}

Expected<mesh::TriMesh> read_tool_mesh(const std::filesystem::path& path) {
  const auto fail = [&](std::string message) -> Expected<mesh::TriMesh> {
    return make_error(ErrorCode::kInvalidMesh, std::move(message), path.string());
  };
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return fail("<tool> mesh: the file is not found");
  auto read = mesh::read_mesh(path);
  if (!read) return std::unexpected(read.error());
  mesh::TriMesh surface;
  surface.vertices = read->mesh.nodes;
  surface.triangles = read->mesh.triangles;
  if (surface.triangles.empty()) return fail("<tool> mesh: the file has no triangles");
  const mesh::SurfaceCheck check = mesh::check_surface(surface);
  if (!check.closed_manifold()) {
    return fail(fmt::format(
        "<tool> mesh is not closed ({} open edges, {} non-manifold edges, {} misoriented edges, "
        "{} degenerate triangles): a tool must have an inside",
        check.boundary_edges, check.non_manifold_edges, check.misoriented_edges, check.degenerate_triangles));
  }
  return surface;
}

Expected<std::shared_ptr<ShapedTool>> ShapedTool::make(const ShapedToolConfig& config, const mesh::TriMesh* mesh,
                                                       double metres_per_unit) {
  if (auto ok = validate(config); !ok) return std::unexpected(ok.error());
  if (!(metres_per_unit > 0.0) || !std::isfinite(metres_per_unit)) {
    return make_error(ErrorCode::kInvalidArgument, "the tool's length unit must be positive");
  }
  const double to_world = 1.0 / metres_per_unit;
  std::vector<ToolPrimitive> primitives;
  const double radius = config.radius_m * to_world;
  switch (config.shape) {
    case ToolShape::kSphere:
      primitives.push_back({Vec3::Zero(), Vec3::Zero(), radius});
      break;
    case ToolShape::kCapsule:
      primitives.push_back({Vec3::Zero(), Vec3(0.0, 0.0, config.length_m * to_world), radius});
      break;
    case ToolShape::kMesh: {
      if (mesh == nullptr || mesh->vertices.empty()) {
        return make_error(ErrorCode::kInvalidArgument, "<tool shape=\"mesh\">: the mesh has no vertices");
      }
      // Sampled as spheres at its vertices and face centroids, evenly thinned to the cap.
      std::vector<Vec3> points = mesh->vertices;
      for (const mesh::Tri& t : mesh->triangles) {
        points.push_back((mesh->vertices[t[0]] + mesh->vertices[t[1]] + mesh->vertices[t[2]]) / 3.0);
      }
      Eigen::AlignedBox3d box;
      for (const Vec3& p : points) box.extend(p);
      const double r = config.radius_m > 0.0 ? radius : 0.01 * box.diagonal().norm() * to_world;
      if (!(r > 0.0)) {
        return make_error(ErrorCode::kInvalidArgument, "<tool shape=\"mesh\">: the mesh has no extent");
      }
      const std::size_t stride = (points.size() + kMaxPrimitives - 1) / kMaxPrimitives;
      for (std::size_t i = 0; i < points.size(); i += stride) {
        primitives.push_back({points[i] * to_world, points[i] * to_world, r});
      }
      break;
    }
  }
  return std::shared_ptr<ShapedTool>(new ShapedTool(config, std::move(primitives), metres_per_unit));
}

ShapedTool::ShapedTool(const ShapedToolConfig& config, std::vector<ToolPrimitive> primitives, double metres_per_unit)
    : config_(config), primitives_(std::move(primitives)), metres_per_unit_(metres_per_unit) {
  const Vec3 axis(config.orientation[0], config.orientation[1], config.orientation[2]);
  if (axis.norm() > 0.0) fixed_ = Eigen::Quaterniond(Eigen::AngleAxisd(config.orientation[3], axis.normalized()));
  double smallest = kInfinity;
  Eigen::AlignedBox3d box;
  for (const ToolPrimitive& p : primitives_) {
    box.extend(p.a);
    box.extend(p.b);
    smallest = std::min(smallest, p.radius);
  }
  bound_centre_ = box.center();
  for (const ToolPrimitive& p : primitives_) {
    bound_radius_ =
        std::max({bound_radius_, (p.a - bound_centre_).norm() + p.radius, (p.b - bound_centre_).norm() + p.radius});
  }
  max_step_ = 0.5 * smallest;
  tolerance_ = 1e-6 * smallest;
  candidates_.resize(kMaxCandidates);
}

void ShapedTool::restart() {
  initialised_ = false;
  candidate_count_ = 0;
}

void ShapedTool::Planes::add(const Vec3& n) {
  for (std::size_t i = 0; i < count; ++i) {
    if (normal[i].dot(n) > 1.0 - 1e-9) return;  // the same plane
  }
  if (count < kMaxPlanes) normal[count++] = n;
}

ShapedTool::Segment::Segment(const Vec3& from, const Vec3& to) : a(from), b(to), d(to - from) {
  const double dd = d.squaredNorm();
  inv_length_squared = dd > 0.0 ? 1.0 / dd : 0.0;
}

double ShapedTool::Segment::distance_squared(const Vec3& p) const {
  const double t = std::clamp((p - a).dot(d) * inv_length_squared, 0.0, 1.0);
  return (p - a - t * d).squaredNorm();
}

bool ShapedTool::may_reach(const Candidate& c, const Segment& s, double radius, double slack) {
  // Both ends on one side of the triangle's plane, at least `radius − slack` from it: the
  // segment is no closer than that to the triangle.
  const double da = c.normal.dot(s.a) - c.offset;
  const double db = c.normal.dot(s.b) - c.offset;
  const double clear = radius - slack;
  if ((da >= clear && db >= clear) || (da <= -clear && db <= -clear)) return false;
  const double reach = c.radius + radius + slack;
  return s.distance_squared(c.centre) <= reach * reach;
}

void ShapedTool::gather(const haptics::ToolTickInput& in, const Mat3& r, const Vec3& from, const Vec3& to) {
  // The box around the whole motion of the shape this tick, from each layer's bound tree: a
  // single primitive (a sphere, a capsule) sweeps its segment from `from` to `to`, and the box
  // of the segment's two placements holds the swept shaft (the box of a thin shaft's
  // neighbourhood, not of its bounding sphere: a capsule lying along an axis gathers a quarter
  // of the sphere's triangles); a mesh tool sweeps its bounding sphere. The margin is the
  // radius and two sub-moves (the pushes move the proxy off the straight path).
  const bool prune = primitives_.size() == 1;
  const ToolPrimitive& p = primitives_.front();
  const double motion = (to - from).norm();
  const double slack = motion + 2.0 * max_step_;
  Eigen::AlignedBox3d box;
  double inflate = 2.0 * max_step_;
  if (prune) {
    box.extend(from + r * p.a);
    box.extend(from + r * p.b);
    box.extend(to + r * p.a);
    box.extend(to + r * p.b);
    inflate += p.radius;
  } else {
    box.extend(from + r * bound_centre_);
    box.extend(to + r * bound_centre_);
    inflate += bound_radius_;
  }
  // The triangles the shaft's own segment may reach (its bounding sphere against the segment
  // where the tick starts, with the motion as slack): fewer exact tests in the pushes.
  const Segment axis(from + r * p.a, from + r * p.b);
  candidate_count_ = 0;
  for (const haptics::SurfaceSnapshot* s : in.surfaces) {
    if (s == nullptr || s->triangles.empty()) continue;
    if (candidate_count_ == kMaxCandidates) break;
    s->tree.visit_overlapping(box.min(), box.max(), inflate, [&](std::int32_t triangle) {
      if (candidate_count_ == kMaxCandidates) return;  // bounded: the rest are not felt this tick
      Candidate& c = candidates_[candidate_count_];
      const mesh::Tri& t = s->triangles[static_cast<std::size_t>(triangle)];
      const Vec3& p0 = s->vertices[t[0]];
      const Vec3& p1 = s->vertices[t[1]];
      const Vec3& p2 = s->vertices[t[2]];
      bounding_sphere(p0, p1, p2, c.centre, c.radius);
      if (prune) {
        const double keep = c.radius + p.radius + slack;
        if (!(axis.distance_squared(c.centre) <= keep * keep)) return;
      }
      c.surface = s;
      c.triangle = triangle;
      const Vec3 n = (p1 - p0).cross(p2 - p0);
      const double area = n.norm();
      c.normal = area > 0.0 && std::isfinite(area) ? Vec3(n / area) : Vec3::Zero();
      c.offset = c.normal.dot(p0);
      ++candidate_count_;
    });
  }
}

double ShapedTool::deepest(const Vec3& position, const Mat3& r) const {
  double worst = 0.0;
  for (const ToolPrimitive& p : primitives_) {
    const Vec3 a = position + r * p.a;
    const Vec3 b = position + r * p.b;
    const Segment segment(a, b);
    for (std::size_t i = 0; i < candidate_count_; ++i) {
      const Candidate& c = candidates_[i];
      if (!may_reach(c, segment, p.radius, tolerance_)) continue;
      const double da = c.normal.dot(a) - c.offset;  // as in resolve: a lower bound first
      const double db = c.normal.dot(b) - c.offset;
      if (da * db > 0.0 && p.radius - std::min(std::abs(da), std::abs(db)) <= worst) continue;
      const mesh::Tri& t = c.surface->triangles[static_cast<std::size_t>(c.triangle)];
      Vec3 on_segment, on_triangle, w;
      const double d = closest_segment_triangle(a, b, c.surface->vertices[t[0]], c.surface->vertices[t[1]],
                                                c.surface->vertices[t[2]], on_segment, on_triangle, w);
      if (d < p.radius) worst = std::max(worst, p.radius - d);
    }
  }
  return worst;
}

bool ShapedTool::resolve(Vec3& position, const Mat3& r, const Vec3& reference, Planes& planes) const {
  // The deepest overlap first, one at a time: on a flat surface of several triangles the
  // deepest is the face under the shape, and pushing it out clears the neighbours' edges
  // (which, pushed first, would tilt the correction and slide the tool).
  for (int push = 0; push < kMaxPushes; ++push) {
    double worst = tolerance_;
    Vec3 push_by = Vec3::Zero();
    for (const ToolPrimitive& p : primitives_) {
      const Vec3 a = position + r * p.a;
      const Vec3 b = position + r * p.b;
      const Segment segment(a, b);
      for (std::size_t i = 0; i < candidate_count_; ++i) {
        const Candidate& c = candidates_[i];
        if (!may_reach(c, segment, p.radius, tolerance_)) continue;
        // The segment's distance to the triangle's plane (both ends on one side) bounds its
        // distance to the triangle from below: a triangle whose plane is no deeper than the
        // deepest overlap found so far cannot be deeper (on a flat patch, the neighbours of
        // the face under the shape: no exact test for them).
        const double da = c.normal.dot(a) - c.offset;
        const double db = c.normal.dot(b) - c.offset;
        if (da * db > 0.0 && p.radius - std::min(std::abs(da), std::abs(db)) <= worst) continue;
        const mesh::Tri& t = c.surface->triangles[static_cast<std::size_t>(c.triangle)];
        const Vec3& p0 = c.surface->vertices[t[0]];
        const Vec3& p1 = c.surface->vertices[t[1]];
        const Vec3& p2 = c.surface->vertices[t[2]];
        Vec3 on_segment, on_triangle, w;
        const double d = closest_segment_triangle(a, b, p0, p1, p2, on_segment, on_triangle, w);
        const double depth = p.radius - d;
        if (!(depth > worst)) continue;
        // Out along the line of the closest points; a shaft crossing the triangle (d ≈ 0)
        // goes back to the side of the triangle's plane the last free pose was on.
        Vec3 n;
        if (d > 1e-9 * p.radius) {
          n = (on_segment - on_triangle) / d;
        } else {
          n = (p1 - p0).cross(p2 - p0).normalized();
          if ((reference + r * (0.5 * (p.a + p.b)) - p0).dot(n) < 0.0) n = -n;
        }
        if (!n.allFinite()) continue;
        worst = depth;
        push_by = depth * n;
      }
    }
    if (worst <= tolerance_) return true;
    position += push_by;
    planes.add(push_by.normalized());
  }
  return deepest(position, r) <= tolerance_;
}

Vec3 ShapedTool::tick(const haptics::ToolTickInput& in, std::span<Vec3> layer_forces, haptics::ToolState& st) {
  // The shape renders every surface: the point renderers' forces are not felt.
  for (Vec3& f : layer_forces) f.setZero();
  const Eigen::Quaterniond q = (in.orientation * fixed_).normalized();
  const Mat3 r = q.toRotationMatrix();
  st.touched = false;
  st.body = -1;
  st.layer = -1;
  st.contact_count = 0;
  st.torque.setZero();
  st.force.setZero();
  st.orientation = q;
  st.axis = r * Vec3(0.0, 0.0, -1.0);
  st.radius = primitives_.front().radius;
  st.length = config_.shape == ToolShape::kCapsule ? (primitives_.front().b - primitives_.front().a).norm() : 0.0;
  const Vec3 x = in.position;
  if (!x.allFinite() || !r.allFinite() || !in.velocity.allFinite()) {
    restart();
    st.tip = proxy_;
    return Vec3::Zero();
  }
  if (!initialised_) {
    proxy_ = last_proxy_ = x;
    proxy_velocity_.setZero();
    initialised_ = true;
  }
  last_proxy_ = proxy_;
  gather(in, r, proxy_, x);
  // Toward the device in sub-moves short enough not to pass through a triangle, each pushed
  // out of what it overlaps. As the god-object does with its constraint planes (Zilles &
  // Salisbury 1995), the motion left loses its part into the planes already met, so the tool
  // slides along them instead of pressing into them again each sub-move; it stops at the
  // projected goal.
  Planes planes;
  Vec3 free = proxy_;
  // A rotation of the device may have turned the shape into a surface: out first.
  if (Vec3 turned = free; resolve(turned, r, free, planes)) free = turned;
  for (int k = 0; k < kMaxSubMoves; ++k) {
    Vec3 d = x - free;
    for (std::size_t i = 0; i < planes.count; ++i) {
      const double into = d.dot(planes.normal[i]);
      if (into < 0.0) d -= into * planes.normal[i];
    }
    const double length = d.norm();
    if (length <= tolerance_) break;
    const bool last = length <= max_step_;
    Vec3 next = last ? Vec3(free + d) : Vec3(free + d * (max_step_ / length));
    const std::size_t met = planes.count;
    if (!resolve(next, r, free, planes)) break;
    free = next;
    if (last && planes.count == met) break;
  }
  proxy_ = free;
  st.tip = proxy_;

  // The contacts at the proxy: touching within a small band.
  const double band = 1e-3 * max_step_ + tolerance_;
  const Vec3 stretch = proxy_ - x;  // > 0 along a normal: the hand pressed in there
  std::array<Vec3, kMaxContacts> points{};
  std::array<double, kMaxContacts> weights{};
  std::array<std::int32_t, kMaxBodies> bodies{};
  std::array<std::int32_t, kMaxBodies> body_layers{};
  std::array<double, kMaxBodies> body_weights{};
  std::size_t body_count = 0;
  std::size_t count = 0;
  Vec3 normal = Vec3::Zero();
  double total = 0.0;
  for (const ToolPrimitive& p : primitives_) {
    const Vec3 a = proxy_ + r * p.a;
    const Vec3 b = proxy_ + r * p.b;
    const Segment segment(a, b);
    for (std::size_t i = 0; i < candidate_count_; ++i) {
      const Candidate& c = candidates_[i];
      if (!may_reach(c, segment, p.radius + band, 0.0)) continue;
      const mesh::Tri& t = c.surface->triangles[static_cast<std::size_t>(c.triangle)];
      Vec3 on_segment, on_triangle, w;
      const double d = closest_segment_triangle(a, b, c.surface->vertices[t[0]], c.surface->vertices[t[1]],
                                                c.surface->vertices[t[2]], on_segment, on_triangle, w);
      if (!(d <= p.radius + band) || !(d > 0.0)) continue;
      const Vec3 n = (on_segment - on_triangle) / d;
      // How far the hand presses along this contact's normal: its share of the force.
      const double weight = std::max(0.0, stretch.dot(n)) + 1e-12;
      total += weight;
      normal += weight * n;
      ++st.contact_count;
      if (count < kMaxContacts) {
        points[count] = on_triangle;
        weights[count] = weight;
        ++count;
      }
      // The body touched most.
      const std::int32_t part = c.surface->part_of(c.triangle);
      std::int32_t body = part;
      if (part >= 0 && c.surface->parts[static_cast<std::size_t>(part)].body >= 0) {
        body = c.surface->parts[static_cast<std::size_t>(part)].body;
      }
      std::int32_t layer = -1;
      for (std::size_t l = 0; l < in.surfaces.size(); ++l) {
        if (in.surfaces[l] == c.surface) layer = static_cast<std::int32_t>(l);
      }
      std::size_t j = 0;
      while (j < body_count && bodies[j] != body) ++j;
      if (j == body_count && body_count < kMaxBodies) {
        bodies[j] = body;
        body_layers[j] = layer;
        body_weights[j] = 0.0;
        ++body_count;
      }
      if (j < body_count) body_weights[j] += weight;
    }
  }
  // The proxy's velocity, low-passed over about one simulation step: the surfaces it rests on
  // move in jumps at the simulation's rate (a new snapshot every ~10 ticks), and the raw
  // difference of one tick turned each jump into a damping spike of b · jump / 1 ms (the force
  // chattered to the device's limit while the hand held still on the liver).
  if (in.dt_s > 0.0) {
    const Vec3 raw = (proxy_ - last_proxy_) / in.dt_s;
    proxy_velocity_ += (in.dt_s / (kProxyVelocityTimeConstant_s + in.dt_s)) * (raw - proxy_velocity_);
  }
  if (st.contact_count == 0) return Vec3::Zero();

  // The virtual coupling (Colgate et al. 1995): spring and damper between proxy and device.
  double k = in.max_stiffness_n_per_m;
  if (config_.stiffness_n_per_m > 0.0) k = std::min(k, config_.stiffness_n_per_m * metres_per_unit_);
  const double b = config_.damping_n_s_per_m * metres_per_unit_;
  Vec3 force = k * stretch + b * (proxy_velocity_ - in.velocity);
  if (!force.allFinite()) force.setZero();
  for (std::size_t i = 0; i < count; ++i) st.torque += (points[i] - x).cross((weights[i] / total) * force);
  std::size_t most = 0;
  for (std::size_t j = 1; j < body_count; ++j) {
    if (body_weights[j] > body_weights[most]) most = j;
  }
  st.touched = true;
  st.body = bodies[most];
  st.layer = body_layers[most];
  st.normal = normal.norm() > 0.0 ? Vec3(normal.normalized()) : Vec3::Zero();
  st.depth_m = stretch.norm() * metres_per_unit_;
  st.force = force;
  return force;
}

ShapedTissueCoupling::ShapedTissueCoupling(std::shared_ptr<const ShapedTool> tool, std::vector<ToolBodySurface> bodies)
    : tool_(std::move(tool)), bodies_(std::move(bodies)) {
  // Sized here for the largest body: a step does not allocate.
  std::size_t most = 0;
  std::size_t triangles = 1;
  for (const ToolBodySurface& b : bodies_) {
    most = std::max(most, b.vertex_count);
    triangles = std::max(triangles, b.triangles.size());
  }
  positions_.resize(most);
  contacts_.reserve(triangles);
}

void ShapedTissueCoupling::add_tissue_forces(const haptics::ToolState& tool, const mechanics::MechanicalModel& model,
                                             const mechanics::MechanicalState& state, std::span<double> forces) {
  (void)model;
  contacts_.clear();
  if (tool.body < 0 || static_cast<std::size_t>(tool.body) >= bodies_.size()) return;
  const ToolBodySurface& body = bodies_[static_cast<std::size_t>(tool.body)];
  if (body.triangles.empty() || body.vertex_count == 0 || !tool.force.allFinite()) return;
  const std::span<Vec3> x(positions_.data(), body.vertex_count);
  body.mapping.apply(std::span<const double>(state.x.data(), static_cast<std::size_t>(state.x.size())), x);
  // The shape where the proxy left it; the band reaches as deep as the hand pressed.
  const Mat3 r = tool.orientation.normalized().toRotationMatrix();
  const double depth = tool.depth_m / tool_->metres_per_unit();
  double smallest = kInfinity;
  for (const ToolPrimitive& p : tool_->primitives()) smallest = std::min(smallest, p.radius);
  const double band = std::max(depth, 0.1 * smallest);
  Contact nearest;
  double nearest_distance = kInfinity;
  double total = 0.0;
  for (std::size_t t = 0; t < body.triangles.size(); ++t) {
    const mesh::Tri& tri = body.triangles[t];
    Vec3 centre;
    double reach = 0.0;
    bounding_sphere(x[tri[0]], x[tri[1]], x[tri[2]], centre, reach);
    Contact best;
    double best_gap = kInfinity;
    for (const ToolPrimitive& p : tool_->primitives()) {
      const Vec3 a = tool.tip + r * p.a;
      const Vec3 b = tool.tip + r * p.b;
      const bool near = point_segment_distance(centre, a, b) <= reach + p.radius + band;
      if (!near && nearest_distance < kInfinity) continue;
      Vec3 on_segment, on_triangle, w;
      const double d = closest_segment_triangle(a, b, x[tri[0]], x[tri[1]], x[tri[2]], on_segment, on_triangle, w);
      if (!std::isfinite(d)) continue;
      if (d - p.radius < nearest_distance) {
        nearest_distance = d - p.radius;
        nearest = {static_cast<std::int32_t>(t), w, on_triangle, 1.0};
      }
      const double gap = d - p.radius;  // < band: in contact
      if (gap < band && gap < best_gap) {
        best_gap = gap;
        best = {static_cast<std::int32_t>(t), w, on_triangle, band - gap};
      }
    }
    if (best.triangle >= 0) {
      contacts_.push_back(best);
      total += best.weight;
    }
  }
  if (contacts_.empty() || !(total > 0.0)) {
    // The tissue has moved away from where the tool was: the reaction at the nearest point.
    if (nearest.triangle < 0) return;
    contacts_.assign(1, nearest);
    total = 1.0;
  }
  const Vec3 reaction = -tool.force;
  for (const Contact& c : contacts_) {
    const Vec3 share = (c.weight / total) * reaction;
    const mesh::Tri& tri = body.triangles[static_cast<std::size_t>(c.triangle)];
    for (int v = 0; v < 3; ++v) body.mapping.add_vertex_force(tri[v], c.barycentric[v] * share, forces);
  }
}

}  // namespace hof::procedures
