// The default probe: a scripted press where a new user would touch a world first — the
// body's surface along its inward normal, to a force under the device's limit — fitted to the
// world's size and the device's workspace; or, with no body, a circle through the force effects.

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "hof/mechanics/model_parameters.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/scene/world.h"

namespace hof::scene {

namespace {
constexpr double kProbeSpeed = 0.02;  // m/s of device travel
}  // namespace

Vec3 default_probe_effects_centre(const haptics::ForceEffects& effects) {
  if (!effects.springs.empty()) return effects.springs.front().position_m;
  for (const haptics::MagneticGeometryEffect& magnet : effects.magnets) {
    if (!magnet.surface || magnet.surface->vertices.empty()) continue;
    // A hand coming from above meets the shape at its top. The probe's (horizontal, 5 mm)
    // circle 5 mm above it stays within the magnet's start distance (H3D's default 1 cm) and
    // about 5 mm from the surface, so it is caught and pulled: about k · 5 mm.
    const Vec3 top =
        *std::ranges::max_element(magnet.surface->vertices, [](const Vec3& a, const Vec3& b) { return a.y() < b.y(); });
    return top + Vec3(0.0, 0.005, 0.0);
  }
  return Vec3::Zero();
}

DefaultProbe default_probe(const std::vector<coupling::SessionBody>& bodies, double workspace_radius_m,
                           double device_stiffness_n_per_m, double max_force_n,
                           const std::array<double, 16>* calibration, double device_max_stiffness_n_per_m,
                           const Vec3& effects_centre, double proxy_radius) {
  DefaultProbe probe;
  probe.calibration = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (bodies.empty()) {
    // Force effects only: circle through them (a still probe feels no viscosity and sits at a
    // spring's rest point), 5 mm around default_probe_effects_centre().
    const Vec3 centre = effects_centre;
    probe.device = fmt::format("scripted:circle,centre={};{};{},radius=0.005,period=1,repeat=0", centre.x(), centre.y(),
                               centre.z());
    probe.description = "no body to press: the probe circles (5 mm, 1 s a turn) through the force effects";
    return probe;
  }
  // Fit the device workspace to the world's bounds (H3D FitToBoxTransform): uniform scale s
  // (world units per device metre) and the centre — unless the file gave a calibration.
  Eigen::AlignedBox3d world_box;
  for (const auto& b : bodies) {
    for (const Vec3& p : b.surface.vertices) world_box.extend(p);
  }
  const double world_radius = std::max(0.5 * world_box.diagonal().norm(), 1e-9);
  if (calibration) {
    probe.calibration = *calibration;
  } else {
    const double fit = world_radius / workspace_radius_m;
    const Vec3 centre = world_box.center();
    probe.calibration = {fit, 0, 0, centre.x(), 0, fit, 0, centre.y(), 0, 0, fit, centre.z(), 0, 0, 0, 1};
  }
  Eigen::Matrix4d C;
  for (int r = 0; r < 4; ++r) {
    for (int k = 0; k < 4; ++k) C(r, k) = probe.calibration[static_cast<std::size_t>(4 * r + k)];
  }
  const double s = std::cbrt(std::abs(C.topLeftCorner<3, 3>().determinant()));
  const Eigen::Matrix4d to_device = C.inverse();

  // The body to press: the first deformable one, else the first.
  const auto target_it = std::find_if(bodies.begin(), bodies.end(), [](const auto& b) { return b.deformable(); });
  const coupling::SessionBody& target = target_it != bodies.end() ? *target_it : bodies.front();
  const mesh::TriMesh& surface = target.surface;
  Eigen::AlignedBox3d box;
  for (const Vec3& p : surface.vertices) box.extend(p);
  const Vec3 c = box.center();
  const double size = box.diagonal().norm();
  // "Up": away from what holds the body (its fixed nodes), else against gravity, else +y.
  Vec3 up = Vec3::UnitY();
  if (target.deformable()) {
    const auto& model = *target.model;
    Vec3 held = Vec3::Zero();
    std::size_t count = 0;
    for (std::size_t i = 0; i < model.node_count(); ++i) {
      if (model.fixed_dof_mask[3 * i] != 0) {
        held += model.rest_positions[i];
        ++count;
      }
    }
    const Vec3 away = count ? Vec3(c - held / static_cast<double>(count)) : Vec3::Zero();
    if (count && away.norm() > 1e-3 * size) {
      up = away.normalized();
    } else if (model.gravity_m_per_s2.norm() > 0.0) {
      up = -model.gravity_m_per_s2.normalized();
    }
  }
  // Where the surface will be when the probe arrives: a body under gravity sags, swings or
  // falls back meanwhile, so its motion without contact is simulated for the approach time
  // (in virtual time the session then reproduces it exactly until the contact).
  constexpr double clearance_dev = 0.02;
  std::vector<Vec3> arrival = surface.vertices;
  if (target.deformable() && target.model->gravity_m_per_s2.norm() > 0.0) {
    mechanics::MechanicalState state = mechanics::make_state(*target.model);
    // At most ~2 million node-steps (a second or two): on a body of a million elements the
    // whole approach would take minutes before the session starts; a shorter look-ahead only
    // makes the press point a little less exact. A count, not a clock, keeps it deterministic.
    constexpr double kMaxNodeSteps = 2e6;
    const auto wanted = static_cast<std::int64_t>(std::ceil(clearance_dev / kProbeSpeed / target.model->dt_s - 1e-9));
    const auto affordable = static_cast<std::int64_t>(
        kMaxNodeSteps / static_cast<double>(std::max<std::size_t>(target.model->node_count(), 1)));
    const std::int64_t steps = std::min(wanted, affordable);
    bool ok = true;
    for (std::int64_t k = 0; k < steps && ok; ++k) ok = mechanics::step(*target.model, state);
    if (ok) target.mapping.apply({state.x.data(), static_cast<std::size_t>(state.x.size())}, arrival);
  }
  Eigen::AlignedBox3d arrival_box;
  for (const Vec3& p : arrival) arrival_box.extend(p);
  const Vec3 arrival_centre = arrival_box.center();
  // Vertex normals of the surface at arrival (area-weighted).
  std::vector<Vec3> normals(arrival.size(), Vec3::Zero());
  for (const mesh::Tri& t : surface.triangles) {
    const Vec3 n = (arrival[t[1]] - arrival[t[0]]).cross(arrival[t[2]] - arrival[t[0]]);
    for (auto v : t) normals[static_cast<std::size_t>(v)] += n;
  }
  // The point to press: where a line down the body's vertical axis (along −up, through the
  // centre of its bounds) first meets the surface from outside — the top middle — as a
  // triangle and barycentric point, so that coarse primitives (a box's four top corners) are
  // pressed on a face, not a corner.
  std::int32_t hit_triangle = -1;
  Vec3 hit_weights = Vec3::Zero();
  {
    const Vec3 from = arrival_centre + size * up;
    const Vec3 segment = -2.0 * size * up;
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      const mesh::Tri& tri = surface.triangles[t];
      const Vec3 a0 = arrival[tri[0]], e1 = arrival[tri[1]] - a0, e2 = arrival[tri[2]] - a0;
      if (e1.cross(e2).dot(up) <= 0.0) continue;  // faces up (outward normal toward the probe)
      // Möller & Trumbore 1997, ray–triangle intersection.
      const Vec3 p = segment.cross(e2);
      const double det = e1.dot(p);
      if (std::abs(det) < 1e-300) continue;
      const Vec3 q = from - a0;
      const double u = q.dot(p) / det;
      const Vec3 qe = q.cross(e1);
      const double v = segment.dot(qe) / det;
      const double along = e2.dot(qe) / det;
      if (u < 0.0 || v < 0.0 || u + v > 1.0 || along < 0.0 || along > 1.0 || along >= nearest) continue;
      nearest = along;
      hit_triangle = static_cast<std::int32_t>(t);
      hit_weights = Vec3(1.0 - u - v, u, v);
    }
  }
  std::size_t best = 0;
  if (hit_triangle < 0) {
    // Nothing on the axis (a ring, say): the vertex on the top that faces up the most, close
    // to the axis.
    double best_score = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < arrival.size(); ++i) {
      if (normals[i].norm() == 0.0) continue;
      const Vec3 n = normals[i].normalized();
      const Vec3 r = arrival[i] - arrival_centre;
      if (r.dot(up) <= 0.0) continue;
      const double score = n.dot(up) - 2.0 * (r - r.dot(up) * up).norm() / size;
      if (score > best_score) {
        best_score = score;
        best = i;
      }
    }
  }
  Vec3 point = arrival[best];
  Vec3 normal = normals[best].norm() > 0.0 ? Vec3(normals[best].normalized()) : up;
  std::array<std::int32_t, 3> press_vertices{static_cast<std::int32_t>(best), 0, 0};
  std::array<double, 3> press_weights{1.0, 0.0, 0.0};
  std::size_t press_count = 1;
  if (hit_triangle >= 0) {
    const mesh::Tri& tri = surface.triangles[static_cast<std::size_t>(hit_triangle)];
    point = hit_weights[0] * arrival[tri[0]] + hit_weights[1] * arrival[tri[1]] + hit_weights[2] * arrival[tri[2]];
    normal = (arrival[tri[1]] - arrival[tri[0]]).cross(arrival[tri[2]] - arrival[tri[0]]).normalized();
    press_vertices = {tri[0], tri[1], tri[2]};
    press_weights = {hit_weights[0], hit_weights[1], hit_weights[2]};
    press_count = 3;
  }
  // A sphere proxy (Ruspini) touches when its centre — the device point — is one radius away.
  point += std::max(0.0, proxy_radius) * normal;
  // Device-frame motion: clearance 2 cm of device travel, then a press deep enough for a
  // force of 40% of the device's limit against the tissue's own stiffness there (its
  // compliance at rest, in series with the rendering spring), 1 to 10 mm, at 2 cm/s, held 1 s.
  // (Deeper presses into soft tissue make the contact jump between the triangles of a sharp
  // dimple, and the force with it: ±30% at 15 mm in the medium FEM liver, ±12% at 10 mm.)
  double compliance_world = 0.0;  // world units per N along the normal
  if (target.deformable()) {
    mechanics::MechanicalState state = mechanics::make_state(*target.model);
    std::array<std::int32_t, coupling::SurfaceMapping::kMaxPointWeights> nodes{};
    std::array<double, coupling::SurfaceMapping::kMaxPointWeights> weights{};
    const std::size_t count = target.mapping.point_weights(
        std::span(press_vertices.data(), press_count), std::span(press_weights.data(), press_count), nodes, weights);
    Mat3 point_compliance;
    // A bounded solve (~2·10⁸ block products): on a body of a million elements an unbounded
    // one takes minutes; without the compliance the press depth is set by the rendering
    // stiffness alone (a shallower, safe press).
    const int max_iterations =
        static_cast<int>(std::clamp(2e8 / (3.0 * static_cast<double>(target.model->node_count())), 50.0, 5000.0));
    if (mechanics::compute_point_compliance(*target.model, state, std::span(nodes.data(), count),
                                            std::span(weights.data(), count), point_compliance, max_iterations) &&
        point_compliance.allFinite()) {
      compliance_world = std::max(0.0, normal.dot(point_compliance * normal));
    }
  }
  // The rendering stiffness of the pressed body's own surface (device_stiffness_n_per_m is the
  // project's surface on this device; a body's own surface is a fraction of the same device).
  const double k_device = std::max(
      target.material ? target.material->stiffness_n_per_m(device_max_stiffness_n_per_m) : device_stiffness_n_per_m,
      1.0);
  const double k_effective = 1.0 / (1.0 / k_device + compliance_world / s);
  const double depth_dev = std::clamp(0.4 * max_force_n / k_effective, 0.001, 0.01);
  // The compliance at rest is only an estimate (a sagging, swinging or contact-stiffened body
  // pushes back harder than it predicts), so the probe also presses to a force, as a hand does:
  // it stops where it first feels half the device's limit, and never rides the safety clamp.
  const double stop_force_n = 0.5 * max_force_n;
  const double approach_dev = clearance_dev;
  const Vec3 start_world = point + clearance_dev * s * normal;
  const Vec3 start_dev = (to_device * start_world.homogeneous()).head<3>();
  const Vec3 direction = (to_device.topLeftCorner<3, 3>() * -normal).normalized();
  probe.device =
      fmt::format("scripted:poke,start={};{};{},direction={};{};{},approach={},depth={},speed={},hold=1,force={}",
                  start_dev.x(), start_dev.y(), start_dev.z(), direction.x(), direction.y(), direction.z(),
                  approach_dev, depth_dev, kProbeSpeed, stop_force_n);
  probe.arrival_s = approach_dev / kProbeSpeed;
  probe.press_s = 2.0 * (approach_dev + depth_dev) / kProbeSpeed + 1.0;
  probe.description = fmt::format(
      "presses body '{}' where its surface will be on arrival, ({:.4g}, {:.4g}, {:.4g}) along its inward normal "
      "({:.3f}, {:.3f}, "
      "{:.3f}), {:.1f} mm of device travel past the surface for about {:.1f} N, stopping earlier "
      "at {:.1f} N (tissue compliance {:.3g} world units/N there); {:.4g} world units per device "
      "metre",
      target.name, point.x(), point.y(), point.z(), direction.x(), direction.y(), direction.z(), 1e3 * depth_dev,
      k_effective * depth_dev, stop_force_n, compliance_world, s);
  return probe;
}

}  // namespace hof::scene
