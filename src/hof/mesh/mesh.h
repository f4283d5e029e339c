#pragma once
/// @file
/// The mesh containers of HoF. One node array is shared by the tetrahedra (the volume) and
/// the triangles (a surface, e.g. the boundary stored in a Gmsh file or a whole OBJ model),
/// so a surface triangle and a tetrahedron that touch the same node use the same index —
/// the shared indexing the thesis' haptic/deformation coupling relies on.

#include <array>
#include <cstdint>
#include <vector>

#include "hof/core/types.h"

namespace hof::mesh {

/// Index of a node in Mesh::nodes (0-based).
using NodeIndex = std::int32_t;
/// A linear tetrahedron: four node indices. Positive orientation means
/// (n1-n0)·((n2-n0)×(n3-n0)) > 0.
using Tet = std::array<NodeIndex, 4>;
/// A triangle: three node indices, counter-clockwise seen from the side its normal points to.
using Tri = std::array<NodeIndex, 3>;

/// A mesh as read from or written to a file.
struct Mesh {
  std::vector<Vec3> nodes;                     ///< (N) node positions, m
  std::vector<Tet> tets;                       ///< (T) tetrahedra
  std::vector<Tri> triangles;                  ///< (F) triangles (surface or stand-alone)
  std::vector<std::int32_t> tet_regions;       ///< empty, or (T) region/physical tag per tet
  std::vector<std::int32_t> triangle_regions;  ///< empty, or (F) region/physical tag per triangle
  std::vector<Vec3> normals;                   ///< empty, or (N) unit normal per node (OBJ `vn`)

  friend bool operator==(const Mesh&, const Mesh&) = default;
};

/// A closed or open triangle surface with its own vertex numbering.
struct TriMesh {
  std::vector<Vec3> vertices;  ///< (V) positions, m
  std::vector<Tri> triangles;  ///< (F) vertex indices, counter-clockwise seen from outside

  friend bool operator==(const TriMesh&, const TriMesh&) = default;
};

}  // namespace hof::mesh
