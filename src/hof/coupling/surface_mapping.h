#pragma once
/// @file
/// Tissue → surface: how the touchable/visual surface follows the simulated volume, and how a
/// force on the surface goes back to the volume's nodes (the transpose of the same map).
///  - by index: surface vertex i is volume node n(i) (the thesis' assumption; checked at
///    build: the positions must coincide);
///  - barycentric (SOFA's BarycentricMapping): each surface vertex is a fixed combination of
///    the four nodes of the tetrahedron that contains it (or the nearest one);
///  - trilinear (SOFA's BarycentricMapping on a hexahedral topology): of the eight nodes of
///    the hexahedron that contains it — a fine surface over a coarse grid.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh.h"

namespace hof::coupling {

class SurfaceMapping {
 public:
  /// Identity by index: `surface_to_volume[i]` is the volume node of surface vertex i. Fails
  /// (naming the first vertex) when a surface vertex is farther than `tolerance_m` from its node.
  static Expected<SurfaceMapping> by_index(std::span<const Vec3> volume_nodes, std::span<const Vec3> surface_vertices,
                                           std::span<const mesh::NodeIndex> surface_to_volume,
                                           double tolerance_m = 1e-9);

  /// Barycentric: each surface vertex in the tetrahedron that contains it, or else the
  /// nearest one (weights then extrapolate, as SOFA does for points outside).
  static Expected<SurfaceMapping> barycentric(std::span<const Vec3> volume_nodes, std::span<const mesh::Tet> tets,
                                              std::span<const Vec3> surface_vertices);

  /// Onto triangles (SOFA's BarycentricMapping on a triangle topology: a membrane, a surface of
  /// springs): each surface vertex gets the barycentric weights of its closest point on the
  /// volume's triangles. As in SOFA, a vertex off the triangles' surface follows its projection
  /// (the offset along the normal is not kept). Errors: no triangles, a node out of range.
  static Expected<SurfaceMapping> onto_triangles(std::span<const Vec3> volume_nodes,
                                                 std::span<const mesh::Tri> triangles,
                                                 std::span<const Vec3> surface_vertices);

  /// Trilinear: each surface vertex gets the trilinear weights N_c(ξ) of the hexahedron that
  /// contains it (ξ found by Newton's method on the trilinear map), or else of the nearest
  /// one (ξ outside [−1, 1]³: the weights extrapolate, as SOFA's mapping does). Errors: no
  /// hexahedra, or a hexahedron with a node out of range.
  static Expected<SurfaceMapping> trilinear(std::span<const Vec3> volume_nodes, std::span<const mesh::Hex> hexes,
                                            std::span<const Vec3> surface_vertices);

  /// Most (node, weight) pairs one surface vertex carries (8, a hexahedron's corners).
  static constexpr std::size_t kMaxNodesPerVertex = 8;
  /// Buffer size for point_weights over a triangle's three vertices.
  static constexpr std::size_t kMaxPointWeights = 3 * kMaxNodesPerVertex;

  /// Surface vertex positions (or velocities) from volume values (3N flat vector).
  void apply(std::span<const double> volume_values, std::span<Vec3> surface_values) const;
  /// Adds a force acting on surface vertex v to the volume forces (3N flat), by the transpose.
  void add_vertex_force(std::int32_t surface_vertex, const Vec3& force, std::span<double> volume_forces) const;

  [[nodiscard]] std::size_t surface_vertex_count() const { return nodes_.size(); }
  [[nodiscard]] bool is_identity() const { return identity_; }
  /// Volume nodes and weights of a point of the surface given as weights over surface vertices
  /// (e.g. a contact triangle's barycentric point); writes up to kMaxNodesPerVertex pairs per
  /// surface vertex (kMaxPointWeights for a triangle), at most the buffers' size; returns the
  /// count.
  std::size_t point_weights(std::span<const std::int32_t> surface_vertices, std::span<const double> surface_weights,
                            std::span<std::int32_t> nodes, std::span<double> weights) const;

  /// The volume node carrying most weight for surface vertex v.
  [[nodiscard]] std::int32_t dominant_node(std::int32_t surface_vertex) const;

 private:
  bool identity_{true};
  int arity_{1};  // nodes per vertex: 1 (by index), 3 (triangle), 4 (tetrahedron) or 8 (hexahedron)
  std::vector<std::array<std::int32_t, kMaxNodesPerVertex>> nodes_;  // (V) volume nodes, first arity_ used
  std::vector<std::array<double, kMaxNodesPerVertex>> weights_;      // (V)
};

}  // namespace hof::coupling
