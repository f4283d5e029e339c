#pragma once
/// @file
/// Boundary surface of a tetrahedral mesh, with the map between surface vertices and volume
/// nodes (the thesis couples haptics and deformation through exactly this shared indexing),
/// and the unique edges of a tetrahedral mesh.

#include <array>
#include <cstdint>
#include <vector>

#include "hof/mesh/mesh.h"

namespace hof::mesh {

/// The boundary of a tet mesh as a stand-alone surface.
struct BoundarySurface {
  /// Surface with its own compact numbering; triangles wind counter-clockwise seen from
  /// outside (outward normals) for positively oriented tets; an inverted tet's faces are
  /// flipped so they still face out of it.
  TriMesh surface;
  /// (V) volume node of each surface vertex, strictly increasing.
  std::vector<NodeIndex> surface_to_volume;
  /// (N) surface vertex of each volume node, or -1 for interior nodes.
  std::vector<std::int32_t> volume_to_surface;
  /// (F) boundary triangles in volume-node indices (same order as surface.triangles).
  std::vector<Tri> volume_triangles;
  /// (F) the tetrahedron each boundary triangle belongs to.
  std::vector<std::int32_t> triangle_tet;
  /// Faces shared by more than two tetrahedra (a non-manifold volume); not in the surface.
  std::int64_t non_manifold_faces{0};
};

/// Extracts the faces that belong to exactly one tetrahedron. Deterministic: triangles come
/// in order of (tet index, local face). Indices must be valid (checked by the readers).
[[nodiscard]] BoundarySurface extract_boundary(const std::vector<Vec3>& nodes, const std::vector<Tet>& tets);

/// Completes a boundary whose volume_triangles (and triangle_tet) are filled and whose
/// volume_to_surface marks every node they use (any value ≥ 0, −1 elsewhere): numbers the
/// surface vertices in increasing volume-node order and builds `surface`. Shared by the
/// tetrahedral and hexahedral boundaries.
void number_boundary_vertices(const std::vector<Vec3>& nodes, BoundarySurface& out);

/// An undirected edge, smaller index first.
using Edge = std::array<NodeIndex, 2>;

/// Unique edges of the tetrahedra, sorted lexicographically.
[[nodiscard]] std::vector<Edge> tet_edges(const std::vector<Tet>& tets);

/// Unique edges of the triangles, sorted lexicographically.
[[nodiscard]] std::vector<Edge> triangle_edges(const std::vector<Tri>& triangles);

}  // namespace hof::mesh
