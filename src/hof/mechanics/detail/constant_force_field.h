#pragma once
/// @file
/// Constant nodal forces, as SOFA's ConstantForceField: either one force per listed node
/// (`forces`) or a total force shared equally by the listed nodes (`totalForce`).

#include <memory>
#include <optional>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/force_field_config.h"

namespace hof::mechanics {

class ConstantForceField final : public ForceField {
 public:
  static Expected<std::unique_ptr<ConstantForceField>> make(std::size_t node_count, const ConstantForceConfig& config,
                                                            std::string name);

  [[nodiscard]] std::string_view type_name() const override { return "ConstantForceField"; }
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>&) const override {}
  void bind(const BlockSparseMatrix&) override {}
  bool add_force_sum_on(const Eigen::VectorXd& x, const Eigen::VectorXd& v, std::span<const std::int32_t> nodes,
                        std::span<const std::uint8_t> in_set, std::vector<std::int32_t>& scratch,
                        Vec3& total) const override;
  void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                 Eigen::VectorXd& f) const override;
  void add_stiffness(const ForceFieldState&, double, BlockSparseMatrix&) const override {}
  [[nodiscard]] bool has_stiffness() const override { return false; }
  /// −Σ f_i·(x_i − x_i(rest)) would need the rest state; the work of a constant force is
  /// accounted as −Σ f_i·x_i, whose changes are what energy checks compare.
  [[nodiscard]] double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const override;

 private:
  ConstantForceField() = default;
  std::vector<std::int32_t> indices_;
  std::vector<Vec3> forces_;
};

}  // namespace hof::mechanics
