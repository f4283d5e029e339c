#include "hof/haptics/haptic_renderer.h"

#include <algorithm>
#include <cmath>

namespace hof::haptics {

namespace {

// The proxy keeps this clearance from the surface (beyond its radius), so that a motion
// along a contact plane never grazes the plane it slides on. 1 µm: far below what a hand
// feels (1 mN at 1000 N/m) and far above round-off at organ scale.
constexpr double kSkin = 1e-6;

}  // namespace

HapticRenderer::HapticRenderer(const RendererConfig& config, const SurfaceMaterial& material,
                               double device_max_stiffness)
    : config_(config),
      material_(material),
      active_(material),
      device_max_stiffness_(device_max_stiffness),
      radius_(config.kind == RendererKind::kRuspini ? std::max(0.0, config.proxy_radius_m) : 0.0) {}

const SurfaceMaterial& HapticRenderer::material_at(const SurfaceSnapshot& surface, std::int32_t t) const {
  if (part_materials_.empty() || t < 0) return material_;
  const std::int32_t part = surface.part_of(t);
  if (part < 0) return material_;
  const std::int32_t body = surface.parts[static_cast<std::size_t>(part)].body;
  const auto index = static_cast<std::size_t>(body >= 0 ? body : part);
  return index < part_materials_.size() ? part_materials_[index] : material_;
}

void HapticRenderer::set_world_scale(double world_per_device_m) {
  const double scale = world_per_device_m > 0.0 && std::isfinite(world_per_device_m) ? world_per_device_m : 1.0;
  config_.ride_distance_m *= scale / world_scale_;
  config_.penalty_max_distance_m *= scale / world_scale_;
  world_scale_ = scale;
}

void HapticRenderer::reconfigure(const RendererConfig& config) {
  config_ = config;
  config_.ride_distance_m *= world_scale_;
  config_.penalty_max_distance_m *= world_scale_;
  radius_ = config.kind == RendererKind::kRuspini ? std::max(0.0, config.proxy_radius_m) : 0.0;
  plane_count_ = 0;
  anchor_ = {};
}

void HapticRenderer::reset(const Vec3& position) {
  proxy_ = position;
  anchor_ = {};
  plane_count_ = 0;
  contact_ = {};
  contact_.proxy = position;
}

const ContactState& HapticRenderer::update(const Vec3& device_position, const Vec3& device_velocity,
                                           const SurfaceSnapshot& surface, bool surface_changed, double dt) {
  // A non-finite device position never moves the proxy: the safety layer zeroes the force.
  if (!device_position.allFinite() || !device_velocity.allFinite()) {
    contact_.in_contact = false;
    contact_.force.setZero();
    return contact_;
  }
  active_ = material_at(surface, contact_.triangle);
  if (config_.kind == RendererKind::kPenalty) {
    update_penalty(device_position, surface);
  } else {
    update_proxy(device_position, surface, surface_changed, dt);
  }
  active_ = material_at(surface, contact_.triangle);
  compute_force(device_position, device_velocity);
  contact_.coupling_force = contact_.force;
  apply_local_model(device_position, surface);
  return contact_;
}

void HapticRenderer::apply_local_model(const Vec3& device, const SurfaceSnapshot& surface) {
  // Compliance coupling: the tissue's reaction to the indentation of its force-free surface.
  const LocalContactModel& local = surface.local;
  if (!local.valid || !contact_.in_contact || active_.kind == SurfaceKind::kZeroForce) return;
  if (local.triangle < 0 || static_cast<std::size_t>(local.triangle) >= surface.triangles.size()) return;
  if (local.direct) {
    // The FEM's own reaction. A frictionless contact only pushes: a tissue still pulling
    // inward (the tool withdrawn faster than it relaxes) lets the tool go.
    const bool pushes = local.reaction.dot(contact_.normal) > 0.0;
    contact_.force = pushes && local.reaction.allFinite() ? local.reaction : Vec3::Zero();
    return;
  }
  const Vec3 free_point = surface.point(local.triangle, local.barycentric) - local.compliance * local.applied_force;
  const Vec3 indentation = free_point - device;
  if (!(indentation.dot(surface.face_normal(local.triangle)) > 0.0)) {
    contact_.force.setZero();
    contact_.coupling_force.setZero();
    return;
  }
  const Vec3 force = local.stiffness * indentation;
  if (force.allFinite()) contact_.force = contact_.coupling_force = force;
}

void HapticRenderer::update_penalty(const Vec3& device, const SurfaceSnapshot& surface) {
  // Force toward the nearest surface point, when the device is behind that point's face.
  const collision::ClosestPoint near = surface.tree.closest_point(
      surface.view(), device, config_.penalty_max_distance_m, collision::TouchableFace::kFrontAndBack);
  contact_.in_contact = false;
  contact_.proxy = device;
  if (near.triangle < 0) return;
  const Vec3 n = surface.face_normal(near.triangle);
  if ((device - near.point).dot(n) >= 0.0) return;
  contact_.in_contact = true;
  contact_.triangle = near.triangle;
  contact_.barycentric = near.barycentric;
  contact_.point = near.point;
  contact_.normal = n;
  contact_.proxy = near.point;
}

void HapticRenderer::carry_with_surface(const SurfaceSnapshot& surface) {
  if (!anchor_.valid || anchor_.triangle < 0 ||
      static_cast<std::size_t>(anchor_.triangle) >= surface.triangles.size()) {
    return;
  }
  const Vec3 n = surface.face_normal(anchor_.triangle);
  const Vec3 carried = surface.point(anchor_.triangle, anchor_.barycentric) + anchor_.offset * n;
  if (carried.allFinite()) proxy_ = carried;
}

void HapticRenderer::push_out_of_surface(const SurfaceSnapshot& surface) {
  // A deforming surface can leave the proxy behind a face: the walls of the dent it makes move
  // between ticks, and a proxy that slid along one wall may end up behind the next. The sweep
  // toward the device starts there, never crosses that front face, and the proxy falls
  // through (seen at 4 mm into the medium liver with the god-object, where a point load's
  // dent has steep walls). So before moving, a proxy whose centre is up to 3 mm behind its
  // nearest face is put back in front of it, a few faces at most. The side is judged by the
  // interpolated vertex normal at the nearest point, which, unlike one face's normal, does
  // not take the space above a convex edge for the inside. A sphere's centre in front of the
  // surface but nearer than its radius is left alone: that is what sliding over an edge looks
  // like, and the sweep resolves it.
  if (config_.touchable_face == collision::TouchableFace::kFrontAndBack) return;  // no inside
  const double side = config_.touchable_face == collision::TouchableFace::kBack ? -1.0 : 1.0;
  constexpr double kReach = 3e-3;  // deeper than this is not a slip: leave it to the sweep
  for (int attempt = 0; attempt < 3; ++attempt) {
    const collision::ClosestPoint near =
        surface.tree.closest_point(surface.view(), proxy_, radius_ + kReach, collision::TouchableFace::kFrontAndBack);
    if (near.triangle < 0) return;
    const Vec3 n = side * surface.shaded_normal(near.triangle, near.barycentric);
    if (!n.allFinite() || (proxy_ - near.point).dot(n) >= 0.0) return;
    const Vec3 pushed = near.point + (radius_ + kSkin) * n;
    if (!pushed.allFinite()) return;
    proxy_ = pushed;
  }
}

void HapticRenderer::anchor_to_surface(const SurfaceSnapshot& surface) {
  const double reach = std::max(config_.ride_distance_m, radius_ + 10.0 * kSkin);
  const collision::ClosestPoint near =
      surface.tree.closest_point(surface.view(), proxy_, reach, collision::TouchableFace::kFrontAndBack);
  anchor_.valid = near.triangle >= 0;
  if (!anchor_.valid) return;
  anchor_.triangle = near.triangle;
  anchor_.barycentric = near.barycentric;
  anchor_.offset = (proxy_ - near.point).dot(surface.face_normal(near.triangle));
}

void HapticRenderer::constrained_motion(const Vec3& goal, const SurfaceSnapshot& surface) {
  plane_count_ = 0;
  Vec3 target = goal;
  const collision::TriangleMeshView view = surface.view();
  for (int iteration = 0; iteration < config_.max_iterations; ++iteration) {
    const collision::SweepHit hit =
        radius_ > 0.0 ? surface.tree.first_hit_swept_sphere(view, proxy_, target, radius_, config_.touchable_face)
                      : surface.tree.first_hit_segment(view, proxy_, target, config_.touchable_face);
    if (hit.triangle < 0) {
      proxy_ = target;
      return;
    }
    // Advance to the contact, then make sure the proxy keeps its clearance.
    Vec3 at = proxy_ + hit.t * (target - proxy_);
    const Vec3& n = hit.normal;
    const double clearance = n.dot(at - hit.point);
    if (clearance < radius_ + kSkin) at += (radius_ + kSkin - clearance) * n;
    proxy_ = at;
    // Record the plane (a triangle already constraining the proxy is refreshed in place).
    std::size_t slot = plane_count_;
    for (std::size_t i = 0; i < plane_count_; ++i) {
      if (plane_triangles_[i] == hit.triangle) slot = i;
    }
    if (slot == plane_count_) {
      if (plane_count_ == planes_.size()) {
        // Three planes already: the oldest gives way (a proxy in a corner is held by three).
        for (std::size_t i = 1; i < planes_.size(); ++i) {
          planes_[i - 1] = planes_[i];
          plane_triangles_[i - 1] = plane_triangles_[i];
          plane_points_[i - 1] = plane_points_[i];
          plane_barycentrics_[i - 1] = plane_barycentrics_[i];
        }
        slot = planes_.size() - 1;
      } else {
        ++plane_count_;
      }
    }
    planes_[slot] = HalfSpace{n, n.dot(hit.point) + radius_ + kSkin};
    plane_triangles_[slot] = hit.triangle;
    plane_points_[slot] = hit.point;
    plane_barycentrics_[slot] = hit.barycentric;
    // Slide: the nearest point to the goal that respects every contact plane.
    target = project_onto_half_spaces(goal, planes_, plane_count_, proxy_);
    if ((target - proxy_).squaredNorm() < 1e-24) return;
  }
}

void HapticRenderer::apply_friction(const Vec3& device, const Vec3& frictionless, const SurfaceSnapshot& surface,
                                    double dt) {
  // Ruspini et al. 1997 §4 / HAPI FrictionSurface: stick while the tangential force stays in
  // the static cone; otherwise slide toward the frictionless proxy at v = (Ft − μd·Fn)/b.
  const Vec3& start = contact_.proxy;  // proxy at the start of the tick (carried with the surface)
  const Vec3 n = contact_.normal;
  const double k = stiffness_n_per_m();
  const double normal_force = k * std::max(0.0, (frictionless - device).dot(n));
  const Vec3 offset = start - device;
  const double tangential_force = k * (offset - offset.dot(n) * n).norm();
  // The start point must still satisfy the contact planes (it may not after a new contact).
  bool start_feasible = true;
  for (std::size_t i = 0; i < plane_count_; ++i) {
    start_feasible = start_feasible && planes_[i].normal.dot(start) >= planes_[i].offset - 1e-9;
  }
  if (!start_feasible) return;
  if (tangential_force <= active_.static_friction * normal_force) {
    proxy_ = start;  // static friction holds
    return;
  }
  constexpr double kSlideDamping = 1.0;  // b in v = (Ft − μd Fn)/b, N·s/m (HAPI)
  const double speed = (tangential_force - active_.dynamic_friction * normal_force) / kSlideDamping;
  if (!(speed > 0.0)) {
    proxy_ = start;
    return;
  }
  const Vec3 path = frictionless - start;
  const double length = path.norm();
  const double step = speed * dt;
  if (length <= step || !(length > 0.0)) return;  // reaches the frictionless proxy this tick
  // Advance part of the way; the path lies on the contact planes, but check the geometry.
  const Vec3 target = start + path * (step / length);
  proxy_ = start;
  const std::size_t saved_count = plane_count_;
  const auto saved_planes = planes_;
  const auto saved_triangles = plane_triangles_;
  constrained_motion(target, surface);
  if (plane_count_ == 0) {
    plane_count_ = saved_count;
    planes_ = saved_planes;
    plane_triangles_ = saved_triangles;
  }
}

void HapticRenderer::update_proxy(const Vec3& device, const SurfaceSnapshot& surface, bool surface_changed, double dt) {
  const bool was_in_contact = contact_.in_contact;
  const Vec3 previous_normal = contact_.normal;
  // 1. Ride with the surface: the proxy keeps its place relative to the triangle it was on,
  //    and stays in front of the faces around it.
  if (surface_changed) carry_with_surface(surface);
  if (was_in_contact) push_out_of_surface(surface);
  contact_.proxy = proxy_;

  // 2. Move toward the device through free space, sliding along the contact planes.
  constrained_motion(device, surface);
  bool in_contact = plane_count_ > 0;

  // 3. Magnetic surfaces hold the proxy to the surface while the device is within the snap
  //    distance of the last contact plane.
  const SurfaceMaterial& anchored = anchor_.valid ? material_at(surface, anchor_.triangle) : material_;
  if (!in_contact && was_in_contact && anchored.kind == SurfaceKind::kMagnetic && anchor_.valid) {
    const Vec3 q = surface.point(anchor_.triangle, anchor_.barycentric);
    const Vec3 n = surface.face_normal(anchor_.triangle);
    const double height = (device - q).dot(n);
    if (height >= 0.0 && height <= anchored.snap_distance_m + radius_) {
      proxy_ = device - (height - radius_ - kSkin) * n;
      planes_[0] = HalfSpace{n, n.dot(q) + radius_ + kSkin};
      plane_triangles_[0] = anchor_.triangle;
      plane_count_ = 1;
      in_contact = true;
    }
  }

  // Contact point and normal: the surface point nearest the proxy.
  contact_.in_contact = in_contact;
  if (in_contact) {
    const collision::ClosestPoint near =
        surface.tree.closest_point(surface.view(), proxy_, radius_ + 1e-3, collision::TouchableFace::kFrontAndBack);
    if (near.triangle >= 0) {
      contact_.triangle = near.triangle;
      contact_.barycentric = near.barycentric;
      contact_.point = near.point;
      const Vec3 toward = proxy_ - near.point;
      contact_.normal = toward.norm() > 1e-12 ? Vec3(toward.normalized()) : surface.face_normal(near.triangle);
    } else {
      contact_.triangle = plane_triangles_[plane_count_ - 1];
      contact_.point = plane_points_[plane_count_ - 1];
      contact_.barycentric = plane_barycentrics_[plane_count_ - 1];
      contact_.normal = planes_[plane_count_ - 1].normal;
    }
    if (!was_in_contact) contact_.proxy = proxy_;  // no friction on the first tick of a contact
    active_ = material_at(surface, contact_.triangle);
    // 4. Friction acts on where the proxy may slide.
    if (active_.has_friction() && was_in_contact) {
      (void)previous_normal;
      apply_friction(device, proxy_, surface, dt);
    }
    // 5. Force shading (Ruspini 1997 §3.3): a second pass toward the device projected on the
    //    plane of the interpolated normal makes the force direction continuous across edges.
    if (config_.kind == RendererKind::kRuspini && config_.force_shading && contact_.triangle >= 0) {
      const Vec3 shaded = surface.shaded_normal(contact_.triangle, contact_.barycentric);
      const double plane = shaded.dot(contact_.point) + radius_ + kSkin;
      const double below = plane - shaded.dot(device);
      if (below > 0.0) {
        const std::size_t count = plane_count_;
        const auto planes = planes_;
        const auto triangles = plane_triangles_;
        constrained_motion(device + below * shaded, surface);
        plane_count_ = count;
        planes_ = planes;
        plane_triangles_ = triangles;
        contact_.normal = shaded;
      }
    }
  }
  contact_.proxy = proxy_;
  anchor_to_surface(surface);
}

void HapticRenderer::compute_force(const Vec3& device, const Vec3& device_velocity) {
  contact_.force.setZero();
  contact_.penetration_m = 0.0;
  if (!contact_.in_contact) return;
  const Vec3 to_proxy = contact_.proxy - device;
  contact_.penetration_m = std::max(0.0, to_proxy.dot(contact_.normal));
  if (active_.kind == SurfaceKind::kZeroForce) return;
  // HAPI FrictionSurface: F = k (proxy − probe) − d ((n̂·v) n̂), n̂ from probe to proxy.
  Vec3 force = stiffness_n_per_m() * to_proxy;
  const double distance = to_proxy.norm();
  if (distance > 0.0 && active_.damping_n_s_per_m > 0.0) {
    const Vec3 n = to_proxy / distance;
    force -= active_.damping_n_s_per_m / world_scale_ * n.dot(device_velocity) * n;
  }
  contact_.force = force;
}

}  // namespace hof::haptics
