#pragma once
/// @file
/// Von Mises equivalent stress of a tetrahedral body for display (SOFA's
/// TetrahedronFEMForceField `computeVonMisesStress=1` with `showVonMisesStressPerNode`): per
/// element from the corotated small strain, per node the volume-weighted mean of the elements
/// around it. Computed from positions alone, on the caller's thread (the window's), so the
/// simulation pays nothing for it.

#include <span>
#include <string>
#include <vector>

#include "hof/core/types.h"
#include "hof/mechanics/mechanical_model.h"

namespace hof::mechanics {

class VonMisesStress {
 public:
  /// From the model's first tetrahedral force field (linear/co-rotational FEM or Neo-Hookean:
  /// its E, ν and material regions). available() is false for a model without one (springs).
  explicit VonMisesStress(const ModelConfig& config);

  [[nodiscard]] bool available() const { return !elements_.empty(); }
  /// The force field it reads (for legends), "" when not available().
  [[nodiscard]] const std::string& source() const { return source_; }
  /// Per element, Pa, at node positions `x` (3N flat, the model's node order).
  void element_stress(std::span<const double> x, std::vector<double>& out) const;
  /// Per node, Pa: the volume-weighted mean of its elements' stress (0 for a node in none).
  void node_stress(std::span<const double> x, std::vector<double>& out) const;

 private:
  struct Element {
    std::array<std::int32_t, 4> nodes;
    Mat3 rest_inverse;  // D_m⁻¹
    double volume;
    double lambda, mu;  // of the element's own modulus
  };
  std::vector<Element> elements_;
  std::vector<double> node_volume_;  // Σ volumes of the elements around each node
  std::string source_;
  mutable std::vector<double> scratch_;
};

/// Von Mises stress (Pa) of the isotropic linear material (λ, μ) at principal stretches
/// `stretches` (corotated strain εᵢ = sᵢ − 1; σᵢ = λ tr ε + 2μ εᵢ;
/// σ_vM = √(½((σ₁−σ₂)² + (σ₂−σ₃)² + (σ₃−σ₁)²)), e.g. Bower, Applied Mechanics of Solids §3.7).
[[nodiscard]] double von_mises_from_stretches(const Vec3& stretches, double lambda, double mu);

}  // namespace hof::mechanics
