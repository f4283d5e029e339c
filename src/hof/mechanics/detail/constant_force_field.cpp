#include "hof/mechanics/detail/constant_force_field.h"

#include <fmt/format.h>

namespace hof::mechanics {

Expected<std::unique_ptr<ConstantForceField>> ConstantForceField::make(std::size_t node_count,
                                                                       const ConstantForceConfig& config,
                                                                       std::string name) {
  const std::string who = fmt::format("ConstantForceField '{}'", name);
  if (config.indices.empty()) return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: no indices", who));
  for (std::int32_t i : config.indices) {
    if (i < 0 || static_cast<std::size_t>(i) >= node_count) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: index {} is out of range (the model has {} nodes)", who, i, node_count));
    }
  }
  auto field = std::unique_ptr<ConstantForceField>(new ConstantForceField());
  field->set_name(std::move(name));
  field->indices_ = config.indices;
  if (config.total_force) {
    field->forces_.assign(config.indices.size(), *config.total_force / static_cast<double>(config.indices.size()));
  } else if (config.forces.size() == 1) {
    field->forces_.assign(config.indices.size(), config.forces.front());
  } else if (config.forces.size() == config.indices.size()) {
    field->forces_ = config.forces;
  } else {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: {} forces for {} indices (give one per index, one for all, or totalForce)", who,
                                  config.forces.size(), config.indices.size()));
  }
  for (const Vec3& force : field->forces_) {
    if (!force.allFinite()) return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: non-finite force", who));
  }
  return field;
}

bool ConstantForceField::add_force_sum_on(const Eigen::VectorXd&, const Eigen::VectorXd&, std::span<const std::int32_t>,
                                          std::span<const std::uint8_t> in_set, std::vector<std::int32_t>&,
                                          Vec3& total) const {
  for (std::size_t k = 0; k < indices_.size(); ++k) {
    if (in_set[static_cast<std::size_t>(indices_[k])] != 0) total += forces_[k];
  }
  return true;
}

void ConstantForceField::add_force(const Eigen::VectorXd&, const Eigen::VectorXd&, ForceFieldState&,
                                   Eigen::VectorXd& f) const {
  for (std::size_t k = 0; k < indices_.size(); ++k)
    f.segment<3>(3 * static_cast<Eigen::Index>(indices_[k])) += forces_[k];
}

double ConstantForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState&) const {
  double energy = 0.0;
  for (std::size_t k = 0; k < indices_.size(); ++k) {
    energy -= forces_[k].dot(x.segment<3>(3 * static_cast<Eigen::Index>(indices_[k])));
  }
  return energy;
}

}  // namespace hof::mechanics
