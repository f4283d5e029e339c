#pragma once
/// @file
/// The touchable surface as the haptic loop sees it: an immutable snapshot of vertex
/// positions, velocities and normals (world frame, metres) over a fixed triangle topology,
/// with its bounding-volume tree refitted. The simulation thread fills a snapshot slot of a
/// TripleBuffer and publishes it; the haptic thread swaps the latest in between ticks.

#include <cstdint>
#include <span>
#include <vector>

#include "hof/collision/aabb_tree.h"
#include "hof/mesh/mesh.h"

namespace hof::haptics {

/// The tissue's local linear response at the current contact, computed by the simulation
/// with each snapshot (compliance coupling): the haptic loop then renders the tissue's own
/// reaction, F = K (p_free − device), at 1 kHz instead of a rigid-wall spring.
struct LocalContactModel {
  bool valid{false};
  std::int32_t triangle{-1};         ///< contact triangle of the snapshot
  Vec3 barycentric{Vec3::Zero()};    ///< contact point in it
  Mat3 compliance{Mat3::Zero()};     ///< C, m/N
  Mat3 stiffness{Mat3::Zero()};      ///< K = C⁻¹, N/m
  Vec3 applied_force{Vec3::Zero()};  ///< force the simulation applied there (on the tissue), N
  /// FEM-reaction coupling: `reaction` (the tissue's elastic force at the contact after the
  /// last step, N) is felt as it is while in contact; the compliance fields are unused.
  bool direct{false};
  Vec3 reaction{Vec3::Zero()};
};

/// One body's share of a snapshot that holds every touchable surface of the world: its
/// vertices and triangles are contiguous ranges (triangles index the snapshot's vertices).
struct SurfacePart {
  std::int32_t first_vertex{0};
  std::int32_t vertex_count{0};
  std::int32_t first_triangle{0};
  std::int32_t triangle_count{0};
  bool is_static{false};  ///< a rigid, fixed body: its geometry never changes
  bool closed{false};     ///< a closed 2-manifold (it has an inside: fall-through is counted)
  std::int32_t body{-1};  ///< the world's body index (materials are per body); -1: the part index
};

struct SurfaceSnapshot {
  std::vector<Vec3> vertices;        ///< (V) world frame, m
  std::vector<Vec3> velocities;      ///< (V) m/s
  std::vector<Vec3> vertex_normals;  ///< (V) unit, area-weighted average of face normals
  std::vector<mesh::Tri> triangles;  ///< (F) fixed for the life of the scene
  collision::AabbTree tree;
  double time_s{0.0};         ///< simulation time the positions belong to
  std::uint64_t sequence{0};  ///< increases with every publish
  double refit_s{0.0};        ///< time spent refitting this snapshot's tree
  /// Geometry that never changes (no simulation behind it): never considered stale.
  bool is_static{false};
  LocalContactModel local;  ///< compliance coupling (invalid otherwise)
  /// Per body (world order); one part covering everything when built from a single surface.
  std::vector<SurfacePart> parts;

  /// Index of the part (body) that triangle `t` belongs to; -1 when out of range.
  [[nodiscard]] std::int32_t part_of(std::int32_t t) const {
    for (std::size_t i = 0; i < parts.size(); ++i) {
      if (t >= parts[i].first_triangle && t < parts[i].first_triangle + parts[i].triangle_count) {
        return static_cast<std::int32_t>(i);
      }
    }
    return -1;
  }

  [[nodiscard]] collision::TriangleMeshView view() const { return {vertices, triangles}; }
  /// Point of triangle `t` at barycentric weights `w`.
  [[nodiscard]] Vec3 point(std::int32_t t, const Vec3& w) const {
    const mesh::Tri& tri = triangles[t];
    return w[0] * vertices[tri[0]] + w[1] * vertices[tri[1]] + w[2] * vertices[tri[2]];
  }
  /// Velocity of that point.
  [[nodiscard]] Vec3 velocity(std::int32_t t, const Vec3& w) const {
    const mesh::Tri& tri = triangles[t];
    return w[0] * velocities[tri[0]] + w[1] * velocities[tri[1]] + w[2] * velocities[tri[2]];
  }
  /// Unit face normal of triangle t (zero for a degenerate triangle).
  [[nodiscard]] Vec3 face_normal(std::int32_t t) const;
  /// Interpolated (Phong) unit normal at barycentric w: the basis of force shading.
  [[nodiscard]] Vec3 shaded_normal(std::int32_t t, const Vec3& w) const;
};

/// A snapshot of `surface` at rest (velocities zero), tree built with `options`.
[[nodiscard]] SurfaceSnapshot make_snapshot(const mesh::TriMesh& surface,
                                            const collision::AabbTreeOptions& options = {});

/// One snapshot of several surfaces (one part each, in order; `is_static[i]` marks rigid
/// ones), under one bound tree: the haptic loop renders one proxy against all of them.
/// `closed[i]` tells which surfaces have an inside.
[[nodiscard]] SurfaceSnapshot make_snapshot(std::span<const mesh::TriMesh> surfaces, std::span<const bool> is_static,
                                            std::span<const bool> closed,
                                            const collision::AabbTreeOptions& options = {});

/// Producer side: new positions (and velocities, or zero when empty) for the same topology;
/// recomputes vertex normals and refits the tree (rebuilding it when refit degrades it).
/// Reuses the snapshot's storage: no allocation once sized.
void update_snapshot(SurfaceSnapshot& snapshot, std::span<const Vec3> positions, std::span<const Vec3> velocities,
                     double time_s);

/// `to` takes `from`'s positions, velocities, normals, tree and time (the same topology): what
/// update_snapshot would compute from the same positions, at the cost of a copy. For a second
/// reader of the same shape (the window's snapshot beside the haptic loop's). No allocation
/// once sized.
void copy_snapshot_geometry(SurfaceSnapshot& to, const SurfaceSnapshot& from);

}  // namespace hof::haptics
