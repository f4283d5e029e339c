#include "hof/mechanics/topology_change.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include <fmt/format.h>

#include <utility>

#include "hof/mechanics/detail/workspace_setup.h"

namespace hof::mechanics {

namespace {

bool same_pattern(const BlockSparseMatrix& a, const BlockSparseMatrix& b) {
  return a.row_start() == b.row_start() && a.columns() == b.columns();
}

// The physical state of `next` from `before`: surviving nodes keep their motion and their
// coupling input, added ones start at rest where the new config puts them.
MechanicalState map_physical_state(const MechanicalModel& next, const MechanicalState& before,
                                   const std::vector<std::int32_t>& old_node) {
  MechanicalState s;
  const Eigen::Index dofs = 3 * static_cast<Eigen::Index>(next.node_count());
  s.x.resize(dofs);
  s.v = Eigen::VectorXd::Zero(dofs);
  s.f = Eigen::VectorXd::Zero(dofs);
  s.external_force = Eigen::VectorXd::Zero(dofs);
  for (std::size_t i = 0; i < next.node_count(); ++i) {
    const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
    if (const std::int32_t o = old_node[i]; o >= 0) {
      const Eigen::Index ko = 3 * static_cast<Eigen::Index>(o);
      s.x.segment<3>(k) = before.x.segment<3>(ko);
      s.v.segment<3>(k) = before.v.segment<3>(ko);
      s.external_force.segment<3>(k) = before.external_force.segment<3>(ko);
    } else {
      s.x.segment<3>(k) = next.rest_positions[i];
    }
  }
  s.time_s = before.time_s;
  s.steps = before.steps;
  s.divergence = before.divergence;
  // Per-field element data (rotations, tangents) is refreshed by the next force evaluation;
  // only the polar decomposition's warm start is lost, which costs an iteration, not accuracy.
  for (const auto& field : next.force_fields) s.field_states.push_back(field->make_state());
  return s;
}

}  // namespace

std::vector<std::int32_t> surviving_node_map(const std::vector<bool>& kept) {
  std::vector<std::int32_t> old_node;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (kept[i]) old_node.push_back(static_cast<std::int32_t>(i));
  }
  return old_node;
}

Expected<TopologyChangeReport> apply_topology_change(MechanicalModel& model, MechanicalState& state,
                                                     const TopologyChange& change) {
  const std::size_t old_n = model.node_count();
  const std::size_t new_n = change.config.positions.size();
  if (change.old_node.size() != new_n) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("model '{}': a topology change maps {} nodes but the new mesh has {}", model.name,
                                  change.old_node.size(), new_n));
  }
  TopologyChangeReport report;
  std::vector<std::uint8_t> taken(old_n, 0);
  bool identity = new_n == old_n;
  for (std::size_t i = 0; i < new_n; ++i) {
    const std::int32_t o = change.old_node[i];
    if (o < -1 || o >= static_cast<std::int64_t>(old_n)) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("model '{}': a topology change maps node {} to node {} of {}", model.name, i, o, old_n));
    }
    if (o == -1) {
      ++report.added_nodes;
      identity = false;
      continue;
    }
    if (taken[static_cast<std::size_t>(o)]) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("model '{}': a topology change maps node {} twice", model.name, o));
    }
    taken[static_cast<std::size_t>(o)] = 1;
    ++report.surviving_nodes;
    identity = identity && o == static_cast<std::int32_t>(i);
  }
  report.removed_nodes = old_n - report.surviving_nodes;

  // The force fields' element data, the lumped masses, the supports and the pattern are those
  // of the new mesh (build_model: each is a pass over its elements).
  auto built = build_model(change.config);
  if (!built) return std::unexpected(built.error());
  MechanicalModel& next = *built;

  MechanicalState mapped = map_physical_state(next, state, change.old_node);
  // The solver's workspace depends on the nodes' numbering and the matrix pattern only: when
  // neither changed (a change of elements that couples the same nodes) the symbolic
  // factorisation, the CG's thread plan and the coarse space's aggregates are kept; only what
  // was formed from the old values is marked stale.
  report.pattern_changed = !(identity && next.needs_matrix == model.needs_matrix && next.linear.kind == model.linear.kind &&
                             same_pattern(next.pattern, model.pattern));
  if (report.pattern_changed) {
    mapped.work = std::make_unique<detail::SolverWorkspace>();
    mapped.work->arena = std::move(state.work->arena);  // the thread setting stays the body's
    detail::size_workspace(next, mapped);
  } else {
    mapped.work = std::move(state.work);
    mapped.work->system_assembled_step = -1;
    mapped.work->coarse.built_step = -1;
  }
  model = std::move(next);
  state = std::move(mapped);
  return report;
}

}  // namespace hof::mechanics
