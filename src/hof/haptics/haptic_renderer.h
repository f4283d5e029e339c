#pragma once
/// @file
/// Haptic rendering of one touchable surface: from the device position (world frame) to a
/// proxy on the surface and a contact force.
///  - `kPenalty`: vector field, force toward the nearest surface point when behind it. Kept
///    for comparison: it falls through thin parts and pops at edges.
///  - `kGodObject`: a point proxy constrained by up to three surface planes (Zilles &
///    Salisbury, "A constraint-based god-object method for haptic display", IROS 1995).
///  - `kRuspini`: a sphere proxy (H3D RuspiniRenderer proxyRadius, default 0.0025 m) moving in
///    configuration space, with force shading (two passes over interpolated normals) and
///    friction (Ruspini, Kolarov & Khatib, "The haptic display of complex graphical
///    environments", SIGGRAPH 1997).
/// The proxy rides on a moving, deforming surface: it is anchored to a triangle and
/// barycentric point and carried along when a new snapshot arrives, and every motion is a
/// continuous sweep, so neither deformation nor a fast hand lets it fall through.
/// update() runs in the haptic tick: no allocation, bounded iterations.

#include <array>
#include <cstdint>
#include <span>

#include "hof/collision/triangle_mesh_view.h"
#include "hof/haptics/constraint_projection.h"
#include "hof/haptics/surface_material.h"
#include "hof/haptics/surface_snapshot.h"

namespace hof::haptics {

enum class RendererKind : std::uint8_t { kPenalty, kGodObject, kRuspini };

struct RendererConfig {
  RendererKind kind{RendererKind::kRuspini};
  double proxy_radius_m{0.0025};  ///< Ruspini only (H3D default 0.0025 m)
  bool force_shading{true};       ///< Ruspini: interpolated normals (two-pass)
  collision::TouchableFace touchable_face{collision::TouchableFace::kFront};
  int max_iterations{8};                ///< constraint iterations per tick
  double penalty_max_distance_m{0.05};  ///< penalty: how deep it still pushes back
  /// When not touching, the proxy is carried with the surface if it is within this distance
  /// of it (H3D dynamicMode: shapes move the proxy with them).
  double ride_distance_m{0.01};

  bool operator==(const RendererConfig&) const = default;
};

/// What a tick produced.
struct ContactState {
  bool in_contact{false};
  std::int32_t triangle{-1};       ///< contact triangle in the snapshot
  Vec3 barycentric{Vec3::Zero()};  ///< contact point's weights in that triangle
  Vec3 point{Vec3::Zero()};        ///< contact point on the surface, world, m
  Vec3 normal{Vec3::Zero()};       ///< surface normal there (shaded when shading is on)
  Vec3 proxy{Vec3::Zero()};        ///< proxy position (sphere centre for Ruspini), world, m
  Vec3 force{Vec3::Zero()};        ///< force on the device, world, N (before safety)
  double penetration_m{0.0};       ///< |proxy − device| along the normal
  /// The force on the device as the tissue takes it (the tissue feels its opposite): the same
  /// as `force`, except with the FEM-reaction coupling, where `force` is the tissue's own
  /// reaction and this is the renderer's spring that drags the contact point along.
  Vec3 coupling_force{Vec3::Zero()};
};

class HapticRenderer {
 public:
  HapticRenderer(const RendererConfig& config, const SurfaceMaterial& material, double device_max_stiffness);

  /// Places the proxy at `position` (outside the surface) with no contact.
  void reset(const Vec3& position);

  /// One tick. `surface_changed` tells that `surface` is a new snapshot since the last call
  /// (the proxy is then carried with the surface). Returns the contact and its force.
  const ContactState& update(const Vec3& device_position, const Vec3& device_velocity, const SurfaceSnapshot& surface,
                             bool surface_changed, double dt);

  [[nodiscard]] const ContactState& contact() const { return contact_; }
  [[nodiscard]] const RendererConfig& config() const { return config_; }
  [[nodiscard]] const SurfaceMaterial& material() const { return material_; }
  void set_material(const SurfaceMaterial& material) { material_ = active_ = material; }
  /// Per-body materials, indexed by the snapshot's parts (a part beyond the span uses
  /// material()). The span must stay valid until the next call (the haptic loop passes its
  /// current settings slot each tick).
  void set_part_materials(std::span<const SurfaceMaterial> materials) { part_materials_ = materials; }
  /// The material of the body that triangle `t` of `surface` belongs to.
  [[nodiscard]] const SurfaceMaterial& material_at(const SurfaceSnapshot& surface, std::int32_t t) const;
  /// A device with another stable stiffness (relative surface stiffnesses are fractions of it).
  void set_device_max_stiffness(double n_per_m) { device_max_stiffness_ = n_per_m; }
  /// Changes the algorithm or its options; the proxy keeps its place (no allocation).
  void reconfigure(const RendererConfig& config);
  /// World units per metre of device travel (the calibration's scale). Stiffness and damping
  /// are felt at the device (N per metre of the hand's travel, as HAPI renders in device
  /// space), so in world units they are divided by it.
  /// The distances the renderer reasons in (ride distance, penalty reach) are device-side
  /// too: they scale with it.
  void set_world_scale(double world_per_device_m);
  /// Stiffness of the material in contact, N per world unit (N/m in a metre world).
  [[nodiscard]] double stiffness_n_per_m() const {
    return active_.stiffness_n_per_m(device_max_stiffness_) / world_scale_;
  }

 private:
  struct Anchor {
    bool valid{false};
    std::int32_t triangle{-1};
    Vec3 barycentric{Vec3::Zero()};
    double offset{0.0};  // signed distance along the face normal from the surface to the proxy
  };

  void update_penalty(const Vec3& device, const SurfaceSnapshot& surface);
  void update_proxy(const Vec3& device, const SurfaceSnapshot& surface, bool surface_changed, double dt);
  // Moves the proxy from its position toward `goal`, stopping at the surface and sliding along
  // up to three contact planes. Fills planes_/plane_count_ and the last contact.
  void constrained_motion(const Vec3& goal, const SurfaceSnapshot& surface);
  void carry_with_surface(const SurfaceSnapshot& surface);
  void push_out_of_surface(const SurfaceSnapshot& surface);
  void anchor_to_surface(const SurfaceSnapshot& surface);
  void apply_friction(const Vec3& device, const Vec3& frictionless, const SurfaceSnapshot& surface, double dt);
  void compute_force(const Vec3& device, const Vec3& device_velocity);
  void apply_local_model(const Vec3& device, const SurfaceSnapshot& surface);

  RendererConfig config_;
  SurfaceMaterial material_;
  std::span<const SurfaceMaterial> part_materials_;
  SurfaceMaterial active_;  // the material of the body in contact (a copy: the renderer stays copyable)
  double device_max_stiffness_;
  double world_scale_{1.0};
  double radius_;  // 0 for the god-object
  Vec3 proxy_{Vec3::Zero()};
  Anchor anchor_;
  std::array<HalfSpace, 3> planes_{};
  std::array<std::int32_t, 3> plane_triangles_{-1, -1, -1};
  std::array<Vec3, 3> plane_points_{};
  std::array<Vec3, 3> plane_barycentrics_{};
  std::size_t plane_count_{0};
  ContactState contact_;
};

}  // namespace hof::haptics
