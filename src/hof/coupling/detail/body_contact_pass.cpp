#include "hof/coupling/detail/body_contact_pass.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "hof/coupling/detail/world_step.h"

namespace hof::coupling::detail {

namespace {

bool has_elements(const mechanics::MechanicalModel& model) {
  return !model.hexahedra.empty() || !model.tets.empty() || !model.triangles.empty();
}

}  // namespace

double pair_contact_stiffness(const ContactSettings& settings, const BodyCollision& a, const BodyCollision& b) {
  if (a.stiffness_n_per_m && b.stiffness_n_per_m) return std::sqrt(*a.stiffness_n_per_m * *b.stiffness_n_per_m);
  if (a.stiffness_n_per_m) return *a.stiffness_n_per_m;
  if (b.stiffness_n_per_m) return *b.stiffness_n_per_m;
  return settings.stiffness_n_per_m;
}

Expected<void> validate_contacts(const ContactSettings& settings, std::span<const SessionBody> bodies) {
  const auto bad = [](std::string message) { return make_error(ErrorCode::kInvalidArgument, std::move(message)); };
  const auto valid_length = [](double value) { return std::isfinite(value) && value >= 0.0; };
  if (!valid_length(settings.contact_distance_m))
    return bad(fmt::format("contact: contact distance must be ≥ 0 m, got {}", settings.contact_distance_m));
  if (!valid_length(settings.alarm_distance_m))
    return bad(fmt::format("contact: alarm distance must be ≥ 0 m, got {}", settings.alarm_distance_m));
  if (settings.enabled && settings.alarm_distance_m < settings.contact_distance_m) {
    return bad(
        fmt::format("contact: alarm distance {} m is below the contact distance {} m (pairs closer than the "
                    "contact distance would go undetected)",
                    settings.alarm_distance_m, settings.contact_distance_m));
  }
  if (!valid_length(settings.stiffness_n_per_m))
    return bad(fmt::format("contact: stiffness must be ≥ 0 N/m, got {}", settings.stiffness_n_per_m));
  if (!valid_length(settings.friction))
    return bad(fmt::format("contact: friction coefficient must be ≥ 0, got {}", settings.friction));
  const auto count = static_cast<std::int32_t>(bodies.size());
  for (const auto& [first, second] : settings.disabled_pairs) {
    if (first < 0 || second < 0 || first >= count || second >= count) {
      return bad(fmt::format("contact: disabled pair ({}, {}) names a body that does not exist ({} bodies)", first,
                             second, count));
    }
  }
  for (const SessionBody& body : bodies) {
    const BodyCollision& c = body.collision;
    if (c.stiffness_n_per_m && !valid_length(*c.stiffness_n_per_m)) {
      return bad(fmt::format("body '{}': contact stiffness must be ≥ 0 N/m, got {}", body.name, *c.stiffness_n_per_m));
    }
    if (c.sphere_centers.size() != c.sphere_radii.size()) {
      return bad(fmt::format("body '{}': {} sphere centres but {} radii", body.name, c.sphere_centers.size(),
                             c.sphere_radii.size()));
    }
    for (std::size_t s = 0; s < c.sphere_radii.size(); ++s) {
      if (!valid_length(c.sphere_radii[s]) || !c.sphere_centers[s].allFinite())
        return bad(fmt::format("body '{}': sphere {} has radius {} m", body.name, s, c.sphere_radii[s]));
    }
    if (!settings.enabled || !c.enabled) continue;
    const bool surface = !body.surface.triangles.empty() && (c.triangles || c.lines || c.points);
    if (!surface && c.sphere_centers.empty()) {
      return bad(fmt::format("body '{}': a collision model but no surface to collide with (no triangles{})", body.name,
                             body.surface.triangles.empty() ? "" : " enabled, no spheres"));
    }
    if (body.deformable() && !c.sphere_centers.empty() && !has_elements(*body.model)) {
      return bad(fmt::format("body '{}': sphere collision models need elements to map the centres through", body.name));
    }
  }
  return {};
}

void BodyContactPass::init(World& w) {
  active_ = w.config.contacts.enabled;
  if (!active_) return;
  constraints_on_ = w.config.contacts.response == ContactResponse::kFrictionConstraint &&
                    w.config.contacts.experimental_constraint_solver;
  const std::size_t n = w.bodies.size();
  detection_.init(w);
  active_contacts_.reserve(kInitialContactCapacity);
  force_sum_.assign(n, Vec3::Zero());
  contact_count_.assign(n, 0);
  due_.assign(n, 0);
  if (constraints()) {
    constraints_.init(w);
    return;  // no springs: no stiffness entries
  }
  // Room for the stiffness entries of many contacts on each body (a contact point carries at
  // most kMaxPointWeights nodes): filling them then allocates nothing.
  // (It grows past that only when a pass has more.)
  detection_.for_each_body([&](std::size_t b) {
    const BodyRuntime& r = w.bodies[b];
    if (!r.body.deformable()) return;
    stiffness_capacity_ = std::max(stiffness_capacity_,
                                   std::min<std::size_t>(kInitialContactCapacity, 4 * r.body.surface.vertices.size()) *
                                       SurfaceMapping::kMaxPointWeights);
  });
  detection_.for_each_body([&](std::size_t b) {
    BodyRuntime& r = w.bodies[b];
    if (r.body.deformable()) r.state.external_stiffness.reserve(stiffness_capacity_);
  });
}

void BodyContactPass::add_side(World& w, const collision::ContactPoint& side, const Vec3& force,
                               const Mat3& stiffness) {
  const auto b = static_cast<std::size_t>(side.body);
  force_sum_[b] += force;
  ++contact_count_[b];
  BodyRuntime& r = w.bodies[b];
  // A rigid body, a body that does not react (SOFA simulated="0") and a body that does not
  // step this world step take nothing.
  if (!r.body.deformable() || !r.body.collision.simulated || !due_[b]) return;
  std::array<std::int32_t, SurfaceMapping::kMaxPointWeights> nodes{};
  std::array<double, SurfaceMapping::kMaxPointWeights> weights{};
  const std::size_t count = detection_.point_weights(w, side, nodes, weights);
  double* f = r.state.external_force.data();
  for (std::size_t k = 0; k < count; ++k) {
    const auto node = static_cast<std::size_t>(nodes[k]);
    for (int q = 0; q < 3; ++q) f[3 * node + static_cast<std::size_t>(q)] += weights[k] * force[q];
    // The spring at the point p = Σ w_i x_i has the stiffness w_i w_j k n nᵀ between nodes i
    // and j. Its rows are summed onto the diagonal (w_i k n nᵀ at node i: Σ_j w_j = 1), which
    // keeps A's pattern (contacts come and go every step; new off-diagonal blocks would mean a
    // new symbolic analysis), keeps A symmetric positive definite, and gives a rigid motion of
    // the contact's nodes the spring's exact force change.
    if (weights[k] != 0.0) r.state.external_stiffness.push_back({nodes[k], weights[k] * stiffness});
  }
}

void BodyContactPass::apply(World& w, std::span<const char> due, SessionReport& report) {
  if (!active_) return;
  const ContactSettings& settings = w.config.contacts;
  if (constraints()) {
    constraints_.save_start(w, due);  // correct() after the step
    return;
  }
  // Without the (unfinished) constraint solver, friction contacts are penalty springs.
  if (settings.response == ContactResponse::kFrictionConstraint) report.friction_solved_as_penalty = true;
  std::fill(due_.begin(), due_.end(), 0);
  std::copy(due.begin(), due.begin() + static_cast<std::ptrdiff_t>(std::min(due.size(), due_.size())), due_.begin());
  detection_.for_each_body([&](std::size_t b) {
    BodyRuntime& r = w.bodies[b];
    if (!r.body.deformable()) return;
    if (due_[b]) r.state.external_stiffness.clear();  // keeps its capacity
    // A command gave the body a new state (a reset, another model): room again for the
    // entries (and detection forgets where it was, begin_pass).
    if (r.state.external_stiffness.capacity() < stiffness_capacity_)
      r.state.external_stiffness.reserve(stiffness_capacity_);
  });
  detection_.begin_pass(w);
  // The surfaces are where the last step left them (the publisher mapped them after it).
  detection_.detect(w, settings.contact_distance_m, active_contacts_);
  std::fill(force_sum_.begin(), force_sum_.end(), Vec3::Zero());
  std::fill(contact_count_.begin(), contact_count_.end(), 0);
  for (const collision::BodyContact& c : active_contacts_) {
    const auto a = static_cast<std::size_t>(c.a.body), b = static_cast<std::size_t>(c.b.body);
    const double k = pair_contact_stiffness(settings, w.bodies[a].body.collision, w.bodies[b].body.collision);
    // PenalityContactForceField: a spring pushing the two points apart along the normal
    // (from b toward a) by the depth below the contact distance; −∂f/∂x = k n nᵀ while active.
    const Vec3 force = k * (settings.contact_distance_m - c.distance) * c.normal;
    const Mat3 stiffness = k * c.normal * c.normal.transpose();
    add_side(w, c.a, force, stiffness);
    add_side(w, c.b, -force, stiffness);
  }
  detection_.end_pass(w);
  detection_.report_pass(w, contact_count_, force_sum_, active_contacts_.size(), report);
}

void BodyContactPass::correct(World& w, std::span<const char> due, SessionReport& report) {
  if (!active_ || !constraints()) return;
  constraints_.apply(w, detection_, due, report, active_contacts_);
}

}  // namespace hof::coupling::detail
