#pragma once
/// @file
/// Linear-elastic hexahedral FEM, as SOFA's HexahedronFEMForceField: trilinear 8-node
/// elements (SOFA's corner order, see mesh/hex_grid.h), isotropic Hooke law (E, ν), the
/// element stiffness integrated by 2×2×2 Gauss quadrature on the rest shape (any hexahedron,
/// not only boxes). `small` is linear; `large` and `polar` are co-rotational: the element's
/// rotation R is removed before the linear law and put back on the forces,
/// f = −R K (Rᵀ x − x₀), with tangent R K Rᵀ (Nesme, Payan & Faure, "Efficient, physically
/// plausible finite elements", Eurographics 2005 short papers). `large` takes R from the frame
/// of the element's averaged edges along its local x and y (as SOFA's `large`), `polar` from
/// the polar decomposition of the matrix of the element's three averaged edges, relative to
/// its value at rest (as SOFA's `polar`, HexahedronFEMForceField::computeRotationPolar). The
/// latter is the polar rotation of the deformation gradient at the centre only for a cubic
/// cell: for a cell longer on one axis the edges are not divided by their rest lengths.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/detail/element_coloring.h"
#include "hof/mechanics/detail/node_incidence.h"
#include "hof/mechanics/detail/stiffness_writer.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/force_field_config.h"
#include "hof/mesh/hex_grid.h"

namespace hof::mechanics {

class HexahedronFemForceField final : public ForceField {
 public:
  using ElementMatrix = Eigen::Matrix<double, 24, 24>;

  /// Builds the element data from the rest positions. Errors name the component and the
  /// parameter out of range, a per-element list of the wrong length, or the first hexahedron
  /// that uses a missing or repeated node or is degenerate or inverted at rest (a Jacobian
  /// determinant ≤ 0 at a Gauss point).
  static Expected<std::unique_ptr<HexahedronFemForceField>> make(const std::vector<Vec3>& rest_positions,
                                                                 const std::vector<mesh::Hex>& hexes,
                                                                 const HexahedronFemConfig& config, std::string name);

  [[nodiscard]] std::string_view type_name() const override { return "HexahedronFEMForceField"; }
  [[nodiscard]] ForceFieldState make_state() const override;
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const override;
  void bind(const BlockSparseMatrix& pattern) override;
  void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                 Eigen::VectorXd& f) const override;
  void add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  bool set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  bool set_stiffness_single(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  [[nodiscard]] double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const override;
  [[nodiscard]] std::int64_t find_invalid_element(const Eigen::VectorXd& x) const override;
  [[nodiscard]] std::string_view element_noun() const override { return "hexahedron"; }

  [[nodiscard]] const HexahedronFemConfig& config() const { return config_; }
  [[nodiscard]] std::size_t element_count() const { return elements_.size(); }
  /// The rest stiffness of element e (N/m), 24×24 in corner-major order (3c + axis).
  [[nodiscard]] ElementMatrix element_stiffness(std::size_t e) const;
  /// Number of distinct rest stiffness matrices kept (elements of the same shape and Poisson
  /// ratio share one, scaled by their modulus: every cell of a grid shares one).
  [[nodiscard]] std::size_t distinct_stiffness_count() const { return stiffness_.size(); }

 private:
  struct Element {
    std::array<std::int32_t, 8> nodes;
    std::int32_t stiffness;            // index into stiffness_ (computed at E = 1 Pa)
    double young_modulus_pa;           // the element's E: scales its stiffness
    std::array<Vec3, 8> rest_offsets;  // X_c − X̄ (rest corner minus rest centre), m
    Mat3 rest_frame_transposed;        // `large`: edge frame of the rest element, transposed
    Mat3 rest_polar_transposed;        // `polar`: polar rotation of the rest averaged edges, transposed
  };

  HexahedronFemForceField() = default;
  // Rotation of element e at positions x (identity for `small`).
  [[nodiscard]] Mat3 rotation(const Element& e, const std::array<Vec3, 8>& offsets) const;
  // Corner offsets x_c − x̄ of element e at x.
  static std::array<Vec3, 8> current_offsets(const Element& e, const Eigen::VectorXd& x);
  // Unrotated corner displacements u = Rᵀ(x − x̄) − (X − X̄) (24).
  static Eigen::Matrix<double, 24, 1> displacement(const Element& e, const Mat3& r, const std::array<Vec3, 8>& offsets);
  // The stiffness gathered row by row (see the .cpp).
  template <StiffnessTarget kTarget>
  void write_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const;

  HexahedronFemConfig config_;
  std::vector<Element> elements_;
  std::vector<ElementMatrix> stiffness_;
  // stiffness_ again as 64 blocks of three padded columns each (block (a, b) at 8a + b), for
  // the assembly's four-lane arithmetic.
  static constexpr std::size_t kLaneMatrixSize = 64 * 12;
  std::vector<double> stiffness_lanes_;
  ElementColoring coloring_;                         // elements sharing no node, per colour
  NodeIncidence incidence_;                          // per node, its (element, corner) entries
  std::vector<std::array<std::int32_t, 64>> slots_;  // per element, block (a, b) at [8a + b]
  bool covers_pattern_{false};                       // every block of the pattern is ours
  std::size_t node_count_{0};
};

/// Element stiffness of a trilinear hexahedron with corners `rest` (Hex order) and Lamé
/// parameters λ, μ: K_ab = Σ_g det J_g (λ g_a g_bᵀ + μ g_b g_aᵀ + μ (g_a·g_b) I) over the 2×2×2
/// Gauss points, g_c = ∇N_c there (Hughes, "The finite element method", 1987, §3.5 and §4.2).
/// Also the smallest Jacobian determinant met (≤ 0: degenerate or inverted), in `min_det`.
[[nodiscard]] HexahedronFemForceField::ElementMatrix hex_element_stiffness(const std::array<Vec3, 8>& rest,
                                                                           double lambda, double mu, double& min_det);

}  // namespace hof::mechanics
