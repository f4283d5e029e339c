#pragma once
/// @file
/// Contact detection between bodies (SOFA's collision pipeline: a broad phase over the bound
/// trees of every body, refitted each pass as the surfaces deform, then a narrow phase of
/// point–triangle, edge–edge and sphere tests within an alarm distance). Detection only: what
/// a contact does to the bodies (penalty forces, constraints) is the response's business
/// (coupling/). Runs on the simulation thread, never on the haptic tick.
///
/// Interface agreed before the implementation (issue 37); the implementation is
/// body_contacts.cpp.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "hof/collision/aabb_tree.h"
#include "hof/collision/triangle_mesh_view.h"
#include "hof/core/types.h"

namespace hof::collision {

/// What one body offers to detection in a pass (the collision models of one SOFA node).
struct CollisionBody {
  TriangleMeshView surface;  ///< its surface at the current positions (m); may have no triangles
  /// Its surface vertices' positions at the previous pass (same size as surface.vertices), for
  /// continuous detection: a vertex that crossed another body's triangle between the passes is
  /// reported as penetrating even when it is now beyond the alarm distance (no tunnelling).
  /// Empty: discrete detection only.
  std::span<const Vec3> previous_vertices;
  bool triangles{true};  ///< SOFA TriangleCollisionModel
  bool lines{true};      ///< SOFA LineCollisionModel (edge–edge tests)
  bool points{true};     ///< SOFA PointCollisionModel (its vertices against other triangles)
  /// SOFA SphereCollisionModel: sphere centres (m, current) and radii (m), same size.
  std::span<const Vec3> sphere_centers;
  std::span<const double> sphere_radii;
  bool moving{true};     ///< SOFA `moving`: its positions change (its tree is refitted each pass)
  bool simulated{true};  ///< SOFA `simulated`: it reacts to contacts (false: an obstacle)
  /// SOFA `group`: bodies sharing a group ≥ 0 never collide with each other; −1: no group.
  std::int32_t group{-1};
  bool self_collision{false};  ///< SOFA `selfCollision` (off by default, as in SOFA)
};

struct DetectionSettings {
  double alarm_distance_m{0.0};  ///< SOFA alarmDistance: pairs closer than this are reported, m
};

enum class PrimitiveKind : std::uint8_t { kVertex, kEdge, kTriangle, kSphere };

/// One side of a contact: a point on a primitive of one body.
struct ContactPoint {
  std::int32_t body{-1};  ///< index into the bodies given to detect()
  PrimitiveKind kind{PrimitiveKind::kVertex};
  /// Surface vertex indices (kVertex: [0]; kEdge: [0], [1]; kTriangle: all three), or the
  /// sphere's index in [0] (kSphere). Unused entries are −1.
  std::array<std::int32_t, 3> vertices{-1, -1, -1};
  std::array<double, 3> weights{0.0, 0.0, 0.0};  ///< barycentric weights of the point, sum 1
  Vec3 point{Vec3::Zero()};                      ///< on the primitive's surface, m
};

/// A pair of points, one on each body, closer than the alarm distance (or crossed).
struct BodyContact {
  ContactPoint a;
  ContactPoint b;
  Vec3 normal{Vec3::UnitZ()};  ///< unit, from b toward a: moving a along it separates them
  /// Signed gap along `normal` between the two surfaces (sphere radii subtracted), m; negative
  /// when they interpenetrate.
  double distance{0.0};
};

class ContactDetector {
 public:
  /// Builds the bodies' bound trees for their topology (kept until the next reset). Allocates.
  void reset(std::span<const CollisionBody> bodies, const AabbTreeOptions& tree = {});
  /// Refits the trees of moving bodies to their current positions, then fills `contacts`
  /// (cleared first) with every pair within settings.alarm_distance_m, in an order that
  /// depends only on the input. `bodies` must have the topology given to reset().
  void detect(std::span<const CollisionBody> bodies, const DetectionSettings& settings,
              std::vector<BodyContact>& contacts);

 private:
  std::vector<AabbTree> trees_;
};

}  // namespace hof::collision
