#include "hof/mechanics/forces.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/vector_kernels.h"

namespace hof::mechanics {

void compute_forces(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& x,
                    const Eigen::VectorXd& v, Eigen::VectorXd& f) {
  // Gravity and the coupling input first, then each force field adds its share.
  const Vec3 g = model.gravity_m_per_s2;
  const std::size_t n = model.node_count();
  parallel_chunks(n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
      f.segment<3>(k) = model.node_mass_kg[i] * g + state.external_force.segment<3>(k);
    }
  });
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    model.force_fields[k]->add_force(x, v, state.field_states[k], f);
  }
  detail::project(model, f);
}

Vec3 point_elastic_force(const MechanicalModel& model, MechanicalState& state, std::span<const std::int32_t> nodes,
                         std::span<const double> weights) {
  detail::SolverWorkspace& w = *state.work;
  if (w.node_marks.size() != model.node_count()) w.node_marks.assign(model.node_count(), 0);
  // A node listed twice counts once: the marks are a set.
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (weights[i] > 1e-12) w.node_marks[static_cast<std::size_t>(nodes[i])] = 1;
  }
  Vec3 total = Vec3::Zero();
  bool local = true;
  for (const auto& field : model.force_fields) {
    if (!field->add_force_sum_on(state.x, state.v, nodes, w.node_marks, w.element_scratch, total)) {
      local = false;
      break;
    }
  }
  if (!local) {
    // A field that can only be evaluated whole: the whole pass, then the marked entries.
    Eigen::VectorXd& f = w.k1x;
    f.setZero();
    for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
      model.force_fields[k]->add_force(state.x, state.v, state.field_states[k], f);
    }
    total.setZero();
    for (const std::int32_t n : nodes) {
      if (w.node_marks[static_cast<std::size_t>(n)] == 0) continue;
      total += f.segment<3>(3 * static_cast<Eigen::Index>(n));
      w.node_marks[static_cast<std::size_t>(n)] = 0;
    }
  }
  for (const std::int32_t n : nodes) w.node_marks[static_cast<std::size_t>(n)] = 0;
  return total;
}

double max_residual_force(const MechanicalModel& model, MechanicalState& state) {
  compute_forces(model, state, state.x, state.v, state.f);
  double worst = 0.0;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    worst = std::max(worst, state.f.segment<3>(3 * static_cast<Eigen::Index>(i)).norm());
  }
  return worst;
}

}  // namespace hof::mechanics
