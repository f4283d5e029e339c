#pragma once
/// @file
/// What every tetrahedral force field precomputes at rest: the (positively ordered) nodes,
/// the rest volume and the shape-function gradients b_i (F = Σ x_i b_iᵀ).

#include <Eigen/Core>
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

/// Per-element stiffness weights for a Young's modulus that varies by element (SOFA's
/// `youngModulus` given as a vector; HoF's material regions): element t's weight is
/// E_t / E, with E_t = `per_element[t]`, or `young_modulus_pa` where that is 0. Since λ and μ
/// are both proportional to E at fixed ν, an element's forces, stiffness and energy are its
/// weight times those at E: the force fields fold the weight into the element's volume.
/// Empty `per_element`: every weight is 1. Errors (naming `who`): a list whose length is not
/// the number of elements, or an entry that is negative or not finite.
[[nodiscard]] Expected<std::vector<double>> element_modulus_weights(const std::vector<double>& per_element,
                                                                    double young_modulus_pa, std::size_t element_count,
                                                                    const std::string& who);

/// Position of node n in a flat 3N vector.
[[nodiscard]] inline Vec3 node(const Eigen::VectorXd& x, std::int32_t n) {
  return x.segment<3>(3 * static_cast<Eigen::Index>(n));
}

/// Deformation gradient F = Σ_i x_i b_iᵀ of an element with `nodes` and rest `gradients`,
/// using Σ b_i = 0 to work with edge vectors.
template <class Element>
[[nodiscard]] Mat3 deformation_gradient(const Element& e, const Eigen::VectorXd& x) {
  const Vec3 x0 = node(x, e.nodes[0]);
  return (node(x, e.nodes[1]) - x0) * e.gradients[1].transpose() +
         (node(x, e.nodes[2]) - x0) * e.gradients[2].transpose() +
         (node(x, e.nodes[3]) - x0) * e.gradients[3].transpose();
}

}  // namespace hof::mechanics
