#pragma once
/// @file
/// Membrane FEM on triangles, as SOFA's TriangleFEMForceField and TriangularFEMForceField: a
/// linear triangle under plane stress (or plane strain) in its own plane. `large` is
/// co-rotational: the element frame (x along the first edge, z along the normal) is taken from
/// the current positions, the in-plane displacement is measured in it and the linear law's
/// forces are rotated back (Felippa, "A systematic approach to the element-independent
/// corotational dynamics of finite elements", 2000; Nesme et al., EG 2005, for the QR frame).
/// `small` keeps the rest frame (linear, not invariant to rotations). A membrane has no
/// bending stiffness: an untensioned flat sheet is free across its plane, as in SOFA. Its
/// tangent adds the initial-stress (geometric) term of the tension, t·A·(∇N_aᵀ σ⁺ ∇N_b)·I
/// (Bathe, "Finite Element Procedures", §6.3; compression clamped at 0 as the springs do), so
/// that a pre-tensioned drum skin is stiff across its plane in the implicit solve too.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hof/core/error.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/force_field_config.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

class TriangleFemForceField final : public ForceField {
 public:
  /// Errors name the component and the first triangle that is degenerate, or the parameter
  /// out of range.
  static Expected<std::unique_ptr<TriangleFemForceField>> make(const std::vector<Vec3>& rest_positions,
                                                               const std::vector<mesh::Tri>& triangles,
                                                               const TriangleFemConfig& config, std::string name);

  [[nodiscard]] std::string_view type_name() const override { return config_.sofa_type; }
  [[nodiscard]] ForceFieldState make_state() const override;
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const override;
  void bind(const BlockSparseMatrix& pattern) override;
  void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                 Eigen::VectorXd& f) const override;
  void add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  [[nodiscard]] double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const override;

  [[nodiscard]] const TriangleFemConfig& config() const { return config_; }
  [[nodiscard]] std::size_t element_count() const { return elements_.size(); }

 private:
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Frame = Eigen::Matrix<double, 3, 2>;  // the element plane's x and y axes, as columns
  struct Element {
    std::array<std::int32_t, 3> nodes;
    std::array<Eigen::Vector2d, 3> rest;  // rest corners in the rest frame, corner 0 at the origin
    Frame rest_frame;
    Vec3 rest_origin;                          // rest position of corner 0
    Matrix6 stiffness;                         // t·A·BᵀDB in the element frame, (u0x u0y u1x u1y u2x u2y)
    Eigen::Matrix<double, 3, 6> stress;        // D·B: the Voigt stress (xx, yy, xy) of a displacement
    std::array<Eigen::Vector2d, 3> gradients;  // ∇N_i in the element frame, 1/m
    double thickness_area;                     // t·A of the rest shape × restScale (initial-stress term), m³
    std::array<std::int32_t, 9> slots;         // block (a, b) at 3a + b
  };

  TriangleFemForceField() = default;
  // The element frame at x (large) or the rest frame (small), and the in-plane displacement.
  Frame frame(const Element& e, const Eigen::VectorXd& x) const;
  Eigen::Matrix<double, 6, 1> displacement(const Element& e, const Frame& r, const Eigen::VectorXd& x) const;

  TriangleFemConfig config_;
  std::vector<Element> elements_;
};

}  // namespace hof::mechanics
