#pragma once
/// @file
/// Topological and geometric checks of a triangle surface: is it a closed, consistently
/// oriented 2-manifold with outward normals? Used before meshing (TetGen needs a closed
/// surface) and by `hof mesh info`.

#include <array>
#include <cstdint>
#include <optional>

#include "hof/mesh/mesh.h"

namespace hof::mesh {

struct SurfaceCheck {
  std::int64_t triangles{0};
  std::int64_t vertices_used{0};
  std::int64_t edges{0};
  std::int64_t boundary_edges{0};         ///< edges with one triangle: the surface is open
  std::int64_t non_manifold_edges{0};     ///< edges with three or more triangles
  std::int64_t misoriented_edges{0};      ///< two triangles traverse the edge the same way
  std::int64_t non_manifold_vertices{0};  ///< vertices whose triangles form several fans
  std::int64_t degenerate_triangles{0};   ///< repeated index or zero area
  std::int64_t components{0};             ///< connected pieces (by shared edges)
  std::int64_t euler_characteristic{0};   ///< V - E + F (2 per sphere-like component)
  double area_m2{0.0};
  /// Volume enclosed, by the divergence theorem (m^3); positive when normals point outward.
  double signed_volume_m3{0.0};
  /// First offending edge found (vertex indices), for error messages.
  std::optional<std::array<NodeIndex, 2>> first_bad_edge;

  /// Closed, edge- and vertex-manifold, consistently oriented and without degenerate faces.
  [[nodiscard]] bool closed_manifold() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && misoriented_edges == 0 && non_manifold_vertices == 0 &&
           degenerate_triangles == 0 && triangles > 0;
  }
  /// closed_manifold() and enclosing a positive volume (normals point out).
  [[nodiscard]] bool closed_outward() const { return closed_manifold() && signed_volume_m3 > 0.0; }
};

/// Checks `triangles` over `vertices`. Indices must be in range.
[[nodiscard]] SurfaceCheck check_surface(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles);
[[nodiscard]] inline SurfaceCheck check_surface(const TriMesh& m) { return check_surface(m.vertices, m.triangles); }

}  // namespace hof::mesh
