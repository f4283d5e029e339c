#include "hof/coupling/detail/body_contact_detection.h"

#include <algorithm>
#include <array>

#include "hof/coupling/detail/world_step.h"

namespace hof::coupling::detail {

namespace {

std::size_t point_vertex_count(collision::PrimitiveKind kind) {
  switch (kind) {
    case collision::PrimitiveKind::kVertex:
    case collision::PrimitiveKind::kSphere:
      return 1;
    case collision::PrimitiveKind::kEdge:
      return 2;
    case collision::PrimitiveKind::kTriangle:
      return 3;
  }
  return 0;
}

}  // namespace

void BodyContactDetection::init(World& w) {
  const std::size_t n = w.bodies.size();
  member_of_.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const BodyRuntime& r = w.bodies[i];
    if (!r.body.collision.enabled) continue;
    Member m;
    m.body = i;
    m.previous = r.surface_positions;
    m.spheres = r.body.collision.sphere_centers;
    if (r.body.deformable() && !m.spheres.empty()) {
      // The centres follow the volume as SOFA's BarycentricMapping makes them, by the same maps
      // as the surface: trilinear in hexahedra, barycentric in tetrahedra, onto triangles.
      const mechanics::MechanicalModel& model = *r.body.model;
      auto mapping =
          !model.hexahedra.empty() ? SurfaceMapping::trilinear(model.rest_positions, model.hexahedra, m.spheres)
          : !model.tets.empty()    ? SurfaceMapping::barycentric(model.rest_positions, model.tets, m.spheres)
                                   : SurfaceMapping::onto_triangles(model.rest_positions, model.triangles, m.spheres);
      if (mapping) {  // validate_contacts made sure there are elements
        m.sphere_mapping = std::move(*mapping);
        m.spheres_mapped = true;
      }
    }
    member_of_[i] = static_cast<std::int32_t>(members_.size());
    members_.push_back(std::move(m));
  }
  views_.resize(members_.size());
  for (std::size_t k = 0; k < members_.size(); ++k) {
    const Member& m = members_[k];
    const BodyRuntime& r = w.bodies[m.body];
    const BodyCollision& c = r.body.collision;
    collision::CollisionBody& v = views_[k];
    v.surface = {r.surface_positions, r.body.surface.triangles};
    v.previous_vertices = m.previous;
    v.triangles = c.triangles;
    v.lines = c.lines;
    v.points = c.points;
    v.sphere_centers = m.spheres;
    v.sphere_radii = c.sphere_radii;
    // A rigid body never moves and never reacts: an obstacle (SOFA: moving="0" simulated="0").
    v.moving = r.body.deformable();
    v.simulated = r.body.deformable() && c.simulated;
    v.group = c.group;
    v.self_collision = c.self_collision.value_or(w.config.contacts.self_collision);
  }
  detector_.reset(views_, w.config.tree);
  detected_.reserve(kInitialContactCapacity);
  bodies_ = n;
  pair_disabled_.assign(n * n, 0);
  for (const auto& [first, second] : w.config.contacts.disabled_pairs) {
    const auto a = static_cast<std::size_t>(first), b = static_cast<std::size_t>(second);
    pair_disabled_[a * n + b] = pair_disabled_[b * n + a] = 1;
  }
}

void BodyContactDetection::begin_pass(World& w) {
  for (Member& m : members_) {
    BodyRuntime& r = w.bodies[m.body];
    if (!r.body.deformable()) continue;
    if (r.state.steps < m.steps_seen)
      std::copy(r.surface_positions.begin(), r.surface_positions.end(), m.previous.begin());
    m.steps_seen = r.state.steps;
    if (m.spheres_mapped) {
      m.sphere_mapping.apply({r.state.x.data(), static_cast<std::size_t>(r.state.x.size())}, m.spheres);
    }
  }
}

void BodyContactDetection::detect(World& w, double within, std::vector<collision::BodyContact>& contacts) {
  contacts.clear();
  detector_.detect(views_, {w.config.contacts.alarm_distance_m}, detected_);
  const std::size_t n = w.bodies.size();
  for (collision::BodyContact c : detected_) {
    if (!(c.distance < within)) continue;
    // Detector body indices are the members'; from here on they are the world's.
    c.a.body = static_cast<std::int32_t>(members_[static_cast<std::size_t>(c.a.body)].body);
    c.b.body = static_cast<std::int32_t>(members_[static_cast<std::size_t>(c.b.body)].body);
    const auto a = static_cast<std::size_t>(c.a.body), b = static_cast<std::size_t>(c.b.body);
    if (pair_disabled_[a * n + b]) continue;
    contacts.push_back(c);
  }
}

void BodyContactDetection::end_pass(World& w) {
  for (Member& m : members_) {
    const BodyRuntime& r = w.bodies[m.body];
    std::copy(r.surface_positions.begin(), r.surface_positions.end(), m.previous.begin());
  }
}

std::size_t BodyContactDetection::point_weights(const World& w, const collision::ContactPoint& side,
                                                std::span<std::int32_t> nodes, std::span<double> weights) const {
  const auto b = static_cast<std::size_t>(side.body);
  const BodyRuntime& r = w.bodies[b];
  if (!r.body.deformable()) return 0;
  if (side.kind == collision::PrimitiveKind::kSphere) {
    const std::int32_t member = member_of_[b];
    if (member < 0 || !members_[static_cast<std::size_t>(member)].spheres_mapped) return 0;
    const std::array<double, 1> one{1.0};
    return members_[static_cast<std::size_t>(member)].sphere_mapping.point_weights(std::span(side.vertices.data(), 1),
                                                                                   one, nodes, weights);
  }
  const std::size_t vertices = point_vertex_count(side.kind);
  return r.body.mapping.point_weights(std::span(side.vertices.data(), vertices),
                                      std::span(side.weights.data(), vertices), nodes, weights);
}

void BodyContactDetection::report_pass(World& w, std::span<const std::int64_t> contact_count,
                                       std::span<const Vec3> force_sum, std::size_t contacts,
                                       SessionReport& report) const {
  for (const Member& m : members_) {
    BodyReport& br = w.bodies[m.body].report;
    br.body_contacts = contact_count[m.body];
    br.max_body_contacts = std::max(br.max_body_contacts, br.body_contacts);
    br.body_contact_force_n = force_sum[m.body];
    br.max_body_contact_force_n = std::max(br.max_body_contact_force_n, force_sum[m.body].norm());
  }
  report.body_contacts = static_cast<std::int64_t>(contacts);
  report.max_body_contacts = std::max(report.max_body_contacts, report.body_contacts);
}

}  // namespace hof::coupling::detail
