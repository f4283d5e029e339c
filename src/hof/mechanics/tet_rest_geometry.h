#pragma once
/// @file
/// What every tetrahedral force field precomputes at rest: the (positively ordered) nodes,
/// the rest volume and the shape-function gradients b_i (F = Σ x_i b_iᵀ).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

struct TetRestGeometry {
  std::array<std::int32_t, 4> nodes;  ///< as given, or with 2 and 3 swapped if inverted at rest
  double volume;                      ///< m^3, > 0
  std::array<Vec3, 4> gradients;      ///< b_i, 1/m; b_0 = −(b_1 + b_2 + b_3)
};

/// Rest geometry of tet `index`. An element inverted at rest is reordered (many files use the
/// opposite orientation; the physics does not depend on node order). Errors name `who`, the
/// element and its nodes: a node out of range, a degenerate element.
[[nodiscard]] Expected<TetRestGeometry> tet_rest_geometry(const std::vector<Vec3>& rest_positions, const mesh::Tet& tet,
                                                          std::size_t index, const std::string& who);

}  // namespace hof::mechanics
