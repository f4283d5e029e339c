#include "hof/mechanics/detail/tet_rest_geometry.h"

#include <fmt/format.h>

#include <cmath>

namespace hof::mechanics {

Expected<TetRestGeometry> tet_rest_geometry(const std::vector<Vec3>& rest_positions, const mesh::Tet& tet,
                                            std::size_t index, const std::string& who) {
  TetRestGeometry g{};
  g.nodes = tet;
  for (std::int32_t n : g.nodes) {
    if (n < 0 || static_cast<std::size_t>(n) >= rest_positions.size()) {
      return make_error(ErrorCode::kInvalidMesh, fmt::format("{}: tetrahedron {} refers to node {} of {}", who, index,
                                                             n, rest_positions.size()));
    }
  }
  const Vec3& p0 = rest_positions[g.nodes[0]];
  Mat3 dm;
  dm.col(0) = rest_positions[g.nodes[1]] - p0;
  dm.col(1) = rest_positions[g.nodes[2]] - p0;
  dm.col(2) = rest_positions[g.nodes[3]] - p0;
  const double det = dm.determinant();
  const double scale = dm.colwise().norm().maxCoeff();
  if (!(std::abs(det) > 1e-12 * scale * scale * scale)) {
    return make_error(ErrorCode::kInvalidMesh,
                      fmt::format("{}: tetrahedron {} (nodes {} {} {} {}) is degenerate at rest (volume {:.3g} m^3)",
                                  who, index, g.nodes[0], g.nodes[1], g.nodes[2], g.nodes[3], det / 6.0));
  }
  if (det < 0.0) {
    std::swap(g.nodes[2], g.nodes[3]);
    dm.col(1).swap(dm.col(2));
  }
  g.volume = std::abs(det) / 6.0;
  // Rows of D_m⁻¹ are the gradients of the shape functions of nodes 1..3.
  const Mat3 dm_inv = dm.inverse();
  g.gradients[1] = dm_inv.row(0).transpose();
  g.gradients[2] = dm_inv.row(1).transpose();
  g.gradients[3] = dm_inv.row(2).transpose();
  g.gradients[0] = -(g.gradients[1] + g.gradients[2] + g.gradients[3]);
  return g;
}

Expected<std::vector<double>> element_modulus_weights(const std::vector<double>& per_element, double young_modulus_pa,
                                                      std::size_t element_count, const std::string& who) {
  std::vector<double> weights(element_count, 1.0);
  if (per_element.empty()) return weights;
  if (per_element.size() != element_count) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: youngModulus lists {} values; a per-element list needs one per element ({})",
                                  who, per_element.size(), element_count));
  }
  for (std::size_t t = 0; t < element_count; ++t) {
    const double e = per_element[t];
    if (!(e >= 0.0) || !std::isfinite(e)) {
      return make_error(
          ErrorCode::kInvalidArgument,
          fmt::format("{}: youngModulus of tetrahedron {} must be > 0 Pa (0: the field's own), got {}", who, t, e));
    }
    weights[t] = e > 0.0 ? e / young_modulus_pa : 1.0;
  }
  return weights;
}

}  // namespace hof::mechanics
