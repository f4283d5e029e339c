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
  ///
  /// What is reported, in this order for each broad-phase pair (i ≤ j, lexicographic; pairs
  /// sharing a group ≥ 0, pairs of two non-simulated bodies and i = j without self_collision
  /// are skipped):
  ///   1. each vertex of i (points) against the triangles of j (triangles): the closest point
  ///      within the alarm distance (a: kVertex of i, b: kTriangle of j), vertex order;
  ///   2. the same with i and j swapped (i ≠ j);
  ///   3. each edge of i (lines) against the edges of j (lines) whose closest points are both
  ///      interior to their edges (endpoints are 1./2.'s business), edge order;
  ///   4. spheres of i against triangles of j, spheres of j against triangles of i, spheres
  ///      of i against spheres of j (i ≠ j).
  /// The sign: a vertex (sphere centre) behind the front face of its closest triangle is
  /// penetrating; for an edge pair, the side is judged by the normals of the triangles
  /// adjacent to each edge. Continuous (i ≠ j, needs previous_vertices): a vertex whose
  /// motion since the previous pass crossed a front face of j is reported whatever its depth
  /// (distance = its signed distance to that triangle's plane, normal = the face normal),
  /// and again at each later pass while its closest point on j's surface is in front of it
  /// (it is still behind j's surface; distance = −the distance to that point). The motion is
  /// judged against j's current surface (j's own motion is caught by j's vertices against i).
  /// Self-collision skips a vertex against the triangles that contain it and those sharing
  /// an edge with them, and edge pairs that share a vertex or such a triangle.
  ///
  /// Bad input never crashes and never puts a NaN in `contacts`: a negative or non-finite
  /// alarm distance counts as 0 (only touching or crossed pairs); a body whose vertex or
  /// triangle count differs from reset(), that has a triangle index out of range at reset(),
  /// or has a non-finite vertex position takes no part in the pass; previous_vertices of the
  /// wrong size or with a non-finite entry are ignored (discrete detection); sphere spans of
  /// different sizes are ignored (no spheres), as are spheres with a non-finite centre or a
  /// negative or non-finite radius; a `bodies` of another size than at reset() gives no
  /// contacts. A body with moving = false is taken to be where it was at reset().
  void detect(std::span<const CollisionBody> bodies, const DetectionSettings& settings,
              std::vector<BodyContact>& contacts);

 private:
  // Per-body data made by reset() (topology) and reused by every detect() (no allocation
  // there except the growth of `contacts` and a tree rebuild that refit() asks for).
  struct BodyState {
    std::size_t vertex_count{0};
    std::size_t triangle_count{0};
    bool valid_topology{false};
    // Unique edges (lower vertex first), sorted; the (up to two) triangles adjacent to each,
    // the first being the lowest index (the edge's owner); each triangle's three edges
    // (edge k joins corners k and k+1; −1 for a degenerate edge).
    std::vector<std::array<std::int32_t, 2>> edges;
    std::vector<std::array<std::int32_t, 2>> edge_triangles;
    std::vector<std::array<std::int32_t, 3>> triangle_edges;
    // Self-collision: per vertex, the sorted triangles it must not be tested against (CSR).
    std::vector<std::int32_t> skip_offsets;
    std::vector<std::int32_t> skip_triangles;
    // Continuous detection: per (vertex, other body), the triangle of the other body this
    // vertex is known to be behind, −1 when none (vertex-major: v·bodies + other).
    std::vector<std::int32_t> inside;
    std::vector<std::int32_t> inside_count;  // per other body: entries of `inside` ≥ 0
    // Per pass.
    bool active{false};
    bool use_previous{false};
    std::size_t sphere_count{0};
    Vec3 lo{Vec3::Zero()};  // box of the vertices (and their previous positions) and spheres
    Vec3 hi{Vec3::Zero()};
  };

  void points_against_triangles(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib, double alarm,
                                std::vector<BodyContact>& contacts);
  void edges_against_edges(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib, double alarm,
                           std::vector<BodyContact>& contacts) const;
  void spheres_against_triangles(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib, double alarm,
                                 std::vector<BodyContact>& contacts) const;
  void spheres_against_spheres(std::span<const CollisionBody> bodies, std::int32_t ia, std::int32_t ib, double alarm,
                               std::vector<BodyContact>& contacts) const;

  std::vector<AabbTree> trees_;
  std::vector<BodyState> states_;
};

}  // namespace hof::collision
