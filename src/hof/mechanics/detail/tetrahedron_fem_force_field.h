#pragma once
/// @file
/// Linear-elastic tetrahedral FEM, as SOFA's TetrahedronFEMForceField (and its alias
/// TetrahedralCorotationalFEMForceField): `small` is linear (infinitesimal strain), `large`
/// and `polar` are co-rotational — the element's rotation R is removed before the linear law
/// is applied and put back on the forces (Müller et al., "Stable real-time deformations",
/// SCA 2002; Nesme et al., "Efficient, physically plausible finite elements", EG 2005).
/// `large` takes R from the QR (Gram-Schmidt) frame of the element's first three nodes,
/// `polar` from the polar decomposition of the deformation gradient (warm-started iteration of
/// Müller et al., "A robust method to extract the rotational part of deformations", MIG 2016).

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/detail/node_incidence.h"
#include "hof/mechanics/detail/stiffness_writer.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/force_field_config.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

/// Lamé parameters from E and ν: λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)).
struct Lame {
  double lambda;
  double mu;
};
[[nodiscard]] Lame lame_parameters(double young_modulus_pa, double poisson_ratio);

class TetrahedronFemForceField final : public ForceField {
 public:
  /// Builds the element data from the rest positions. Errors name the component and the first
  /// element that is degenerate or inverted at rest, or the parameter out of range.
  static Expected<std::unique_ptr<TetrahedronFemForceField>> make(const std::vector<Vec3>& rest_positions,
                                                                  const std::vector<mesh::Tet>& tets,
                                                                  const TetrahedronFemConfig& config, std::string name);

  /// The field over a changed mesh (topology_change.h), rebuilding only what the change
  /// touched: element t of the result is element old_element[t] of this one — its rest data
  /// (gradients, volume, frame) kept, its nodes renumbered by new_of_old_node — or, where
  /// old_element[t] is −1, tets[t] built anew from rest_positions (counted in `rebuilt`). The
  /// index structures (incidence, SIMD groups, coupled pairs) are redone from the elements'
  /// node ids. `config` is the field's configuration over the new mesh (its per-element
  /// moduli are read for the new elements only: a kept element keeps its material).
  [[nodiscard]] Expected<std::unique_ptr<TetrahedronFemForceField>> remade(
      const std::vector<Vec3>& rest_positions, const std::vector<mesh::Tet>& tets,
      const std::vector<std::int32_t>& old_element, const std::vector<std::int32_t>& new_of_old_node,
      const TetrahedronFemConfig& config, std::size_t& rebuilt) const;

  [[nodiscard]] std::string_view type_name() const override { return "TetrahedronFEMForceField"; }
  [[nodiscard]] ForceFieldState make_state() const override;
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const override;
  void bind(const BlockSparseMatrix& pattern) override;
  bool add_force_sum_on(const Eigen::VectorXd& x, const Eigen::VectorXd& v, std::span<const std::int32_t> nodes,
                        std::span<const std::uint8_t> in_set, std::vector<std::int32_t>& scratch,
                        Vec3& total) const override;
  void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                 Eigen::VectorXd& f) const override;
  void add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  bool set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  bool set_stiffness_single(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  [[nodiscard]] double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const override;
  [[nodiscard]] std::int64_t find_invalid_element(const Eigen::VectorXd& x) const override;
  [[nodiscard]] std::string_view element_noun() const override { return "tetrahedron"; }

  [[nodiscard]] const TetrahedronFemConfig& config() const { return config_; }
  [[nodiscard]] std::size_t element_count() const { return elements_.size(); }

 private:
  struct Element {
    std::array<std::int32_t, 4> nodes;
    double volume;                  // rest volume × modulus weight (element_modulus_weights), m^3
    std::array<Vec3, 4> gradients;  // shape-function gradients b_i at rest, 1/m
    Mat3 rest_frame_transposed;     // QR frame of the rest element, transposed
  };
  // Four elements side by side for the `large` element pass (one SIMD lane each). Groups are
  // padded with copies of element 0 whose volume is zero, so they produce nothing.
  struct ElementGroup {
    std::int32_t nodes[4][4];     // [corner][lane]
    double rest_gradients[9][4];  // H b_j, j = 1..3, in the rest QR frame: [3(j−1)+q][lane]
    double volume[4];             // V, zero for padding
    double root_volume[4];        // √V
  };
  // One block pair (i, j), i < j, of the stiffness: the slots of (i, j) and (j, i) and the
  // element corners that couple the two nodes, terms [first, last).
  struct EdgeBlocks {
    std::int32_t slot_ij;
    std::int32_t slot_ji;
    std::int32_t first;
    std::int32_t last;
  };

  TetrahedronFemForceField() = default;
  // One element's rest data (tet `index` of the mesh, for messages), its volume weighted by
  // its modulus (element_modulus_weights).
  static Expected<Element> make_element(const std::vector<Vec3>& rest_positions, const mesh::Tet& tet,
                                        std::size_t index, double modulus_weight, const std::string& who);
  // The structures that follow from the elements' node ids (incidence, groups, edges).
  void index_elements(std::size_t node_count);
  // Rotation of element e at positions x (identity for `small`).
  Mat3 rotation(const Element& e, const Mat3& deformation_gradient, const Eigen::VectorXd& x) const;
  // The element's nodal-force map −V R σ at x (f_i = map · b_i), and its rotation R.
  Mat3 element_force_map(const Element& e, const Eigen::VectorXd& x, Mat3& r) const;
  // Per-element pass: corner forces and rotated scaled gradients into `state`.
  void element_pass_large(const Eigen::VectorXd& x, TetrahedronFemState& state) const;
  // Groups [begin, end) of the `large` pass (plain pointers keep the loop in registers).
  static void large_groups(const ElementGroup* groups, std::size_t begin, std::size_t end, const double* xs,
                           double lambda, double two_mu, double* stiffness_vectors, double* corner_forces);
  void element_pass_general(const Eigen::VectorXd& x, TetrahedronFemState& state) const;
  template <StiffnessTarget kTarget>
  void write_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const;

  TetrahedronFemConfig config_;
  Lame lame_{};
  std::vector<Element> elements_;
  std::vector<ElementGroup> groups_;
  // Per node, the element corners that use it (entry = 4·element + corner), for the gathers.
  NodeIncidence incidence_;
  std::vector<EdgeBlocks> edges_;                        // sorted by (i, j)
  std::vector<std::array<std::int32_t, 2>> edge_terms_;  // (entry of i, entry of j)
  std::vector<std::int32_t> diagonal_slots_;             // per node
  bool covers_pattern_{false};                           // every block of the pattern is ours
};

}  // namespace hof::mechanics
