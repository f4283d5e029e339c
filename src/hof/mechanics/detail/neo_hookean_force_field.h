#pragma once
/// @file
/// Compressible Neo-Hookean tetrahedral FEM — the material nonlinearity the thesis leaves as
/// future work. Strain energy density (Bonet & Wood, "Nonlinear continuum mechanics for finite
/// element analysis", 2nd ed., eq. 6.27):
///   W(F) = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²,  I₁ = tr(FᵀF), J = det F,
/// first Piola–Kirchhoff stress P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ.
/// Robust to large compression and inversion (invertible FEM, Irving, Teran & Fedkiw,
/// SCA 2004): F is diagonalised by a rotation-preserving SVD, singular values below a
/// threshold are clamped and the stress extrapolated, so an inverted element is pushed back
/// instead of producing NaN. The tangent stiffness is projected to positive semi-definite
/// (Teran et al., SCA 2005) so implicit and static solvers stay well posed.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/detail/element_coloring.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

class NeoHookeanForceField final : public ForceField {
 public:
  static Expected<std::unique_ptr<NeoHookeanForceField>> make(const std::vector<Vec3>& rest_positions,
                                                              const std::vector<mesh::Tet>& tets,
                                                              const NeoHookeanConfig& config, std::string name);

  [[nodiscard]] std::string_view type_name() const override { return "NeoHookeanForceField"; }
  [[nodiscard]] ForceFieldState make_state() const override;
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const override;
  void bind(const BlockSparseMatrix& pattern) override;
  void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                 Eigen::VectorXd& f) const override;
  void add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  [[nodiscard]] double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const override;

  /// First Piola–Kirchhoff stress of the material at deformation gradient F (Pa), with the
  /// inversion handling applied. Exposed for material tests.
  [[nodiscard]] Mat3 first_piola_stress(const Mat3& deformation_gradient) const;
  /// Strain energy density at F (J/m^3).
  [[nodiscard]] double energy_density(const Mat3& deformation_gradient) const;

 private:
  struct Element {
    std::array<std::int32_t, 4> nodes;
    double volume;  // rest volume × modulus weight (element_modulus_weights), m^3
    std::array<Vec3, 4> gradients;
    std::array<std::int32_t, 16> slots;
  };
  NeoHookeanForceField() = default;

  NeoHookeanConfig config_;
  double lambda_{0.0};
  double mu_{0.0};
  std::vector<Element> elements_;
  ElementColoring coloring_;
};

}  // namespace hof::mechanics
