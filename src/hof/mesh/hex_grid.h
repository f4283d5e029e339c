#pragma once
/// @file
/// Hexahedral grids as SOFA builds them: RegularGridTopology (a box cut into n−1 cells per
/// axis) and SparseGridTopology (the cells of such a box that a closed surface fills or passes
/// through), the boundary of a set of hexahedra, and the volume of a trilinear hexahedron.
/// A coarse hexahedral grid under a fine surface is the thesis' multi-resolution idea: the
/// mechanics run on the grid, the surface follows by trilinear interpolation.

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/types.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh {

/// A trilinear hexahedron: eight node indices in SOFA's corner order. In local cell
/// coordinates (i, j, k) ∈ {0,1}³ the corners are 0:(0,0,0) 1:(1,0,0) 2:(1,1,0) 3:(0,1,0)
/// 4:(0,0,1) 5:(1,0,1) 6:(1,1,1) 7:(0,1,1): 0–3 counter-clockwise seen from +k, 4–7 above
/// them. Positive orientation means the map from the unit cube has a positive Jacobian.
using Hex = std::array<NodeIndex, 8>;

/// Local cell coordinates of the corners of a Hex, as ±1 in the reference cube [−1, 1]³.
inline constexpr std::array<std::array<int, 3>, 8> kHexCornerSigns = {
    {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}}};

/// A grid of hexahedral cells (regular, or the kept cells of a sparse grid).
struct HexGrid {
  std::vector<Vec3> nodes;        ///< (N) node positions, m
  std::vector<Hex> hexes;         ///< (H) hexahedra, positively oriented
  Vec3 min{Vec3::Zero()};         ///< box corner of the full grid, m
  Vec3 max{Vec3::Zero()};         ///< opposite box corner, m
  std::array<int, 3> n{2, 2, 2};  ///< nodes per axis of the full grid (SOFA's `n`); cells n−1
  /// (H) the cell of each hexahedron in the full grid, i + (n₀−1)(j + (n₁−1)k).
  std::vector<std::int32_t> hex_cells;
  /// (H) 1 where the surface passes through the cell (SOFA's BOUNDARY cell), 0 for a cell
  /// inside it (INSIDE) or of a regular grid. SOFA's `fillWeighted` (its default) gives
  /// boundary cells half the stiffness (SparseGridTopology::buildAsFinest sets their stiffness
  /// coefficient to 0.5, which HexahedronFEMForceField multiplies into the element's stiffness
  /// matrix): a per-element youngModulus of E/2 there. Their mass coefficient (also 0.5) is
  /// read only by HexahedronFEMForceFieldAndMass; DiagonalMass, MeshMatrixMass and
  /// UniformMass ignore it.
  std::vector<std::uint8_t> hex_on_surface;

  /// Size of one cell, m.
  [[nodiscard]] Vec3 cell_size() const {
    return {(max.x() - min.x()) / (n[0] - 1), (max.y() - min.y()) / (n[1] - 1), (max.z() - min.z()) / (n[2] - 1)};
  }
};

/// SOFA's RegularGridTopology: the box [min, max] with n[a] nodes along axis a (n[a] ≥ 2),
/// node (i, j, k) at index i + n₀(j + n₁k), (n₀−1)(n₁−1)(n₂−1) hexahedra in cell order.
/// Errors (naming the value): an axis with fewer than 2 nodes, min not below max on an axis,
/// non-finite corners, more than 16 million nodes.
[[nodiscard]] Expected<HexGrid> regular_grid(std::array<int, 3> n, const Vec3& min, const Vec3& max);

/// SOFA's SparseGridTopology built from a closed triangle surface: the surface's bounding box
/// enlarged by 1% of its size on each side (as SOFA does; or `box` = (min, max) when given)
/// is cut into (n−1)³ cells, and a cell is kept when the surface passes through it (triangle /
/// box overlap by separating axes, Akenine-Möller, "Fast 3D triangle-box overlap testing",
/// JGT 2001) or it is inside, by SOFA's rule (SparseGridTopology::voxelizeTriangleMesh): a
/// cell is outside when a flood fill from the grid's outer layer through face neighbours the
/// surface does not cross reaches it, inside otherwise — so a pocket of outside space walled in
/// by crossed cells (a cavity, a fold narrower than a cell) is kept, as SOFA keeps it. A cell
/// whose centre is inside (parity of the crossings of a ray) is kept too: the two rules differ
/// only for a surface lying in grid planes, which HoF does not count as crossing the cells on
/// either side. Unused nodes are dropped. The order is SOFA's, so that indices in a SOFA scene mean the same
/// nodes: the cells the surface crosses first, then the inside ones, each in cell order; the
/// nodes sorted by x, then y, then z.
/// Errors: an empty surface, an index out of range, an open surface (a ray crosses it an
/// unbalanced number of times), a flat bounding box, or no cell kept ("the grid has no cell
/// inside the surface").
[[nodiscard]] Expected<HexGrid> sparse_grid(const TriMesh& closed_surface, std::array<int, 3> n,
                                            const std::optional<std::pair<Vec3, Vec3>>& box = std::nullopt);

/// The faces used by exactly one hexahedron, each quad split into two triangles wound
/// counter-clockwise seen from outside (for positively oriented hexahedra), with the same
/// numbering maps as extract_boundary. `triangle_tet` holds the hexahedron of each triangle.
/// Deterministic: triangles come in order of (hexahedron, local face). Indices must be valid.
[[nodiscard]] BoundarySurface hex_boundary(const std::vector<Vec3>& nodes, const std::vector<Hex>& hexes);

/// Volume of the trilinear hexahedron (m³), signed: 2×2×2 Gauss quadrature of the Jacobian
/// determinant, exact for a trilinear map (the determinant is at most quadratic per axis).
[[nodiscard]] double hex_volume(const std::vector<Vec3>& nodes, const Hex& hex);

/// Trilinear shape functions N_c(ξ) = ⅛ Π_a (1 + s_ca ξ_a) at ξ ∈ [−1, 1]³ (extrapolating
/// outside), corners in Hex order.
[[nodiscard]] std::array<double, 8> hex_shape_functions(const Vec3& xi);

/// Their derivatives ∂N_c/∂ξ (column c), at ξ.
[[nodiscard]] Eigen::Matrix<double, 3, 8> hex_shape_derivatives(const Vec3& xi);

}  // namespace hof::mesh
