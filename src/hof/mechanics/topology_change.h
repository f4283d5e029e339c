#pragma once
/// @file
/// The seam for changes of a body's topology while it runs (cutting, tearing, refinement):
/// elements removed or split, nodes added. A change is the body after it (its ModelConfig:
/// rest positions, elements, materials, supports) and where each of its nodes was before.
/// apply_topology_change() swaps the model for the changed one and carries the motion over:
/// surviving nodes keep their positions, velocities and coupling input; added nodes start at
/// their rest position, at rest. What it rebuilds is listed in docs/architecture.md
/// ("Topology changes"); in short, the physical state is mapped, the force fields, masses and
/// matrix pattern are those of the new mesh, and the solver's workspace (its symbolic
/// factorisation above all) is kept when the pattern did not change.

#include <cstdint>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics {

struct TopologyChange {
  /// The body after the change: the same solvers and materials over the new mesh. Node i of
  /// it is node old_node[i] of the model before.
  ModelConfig config;
  /// (new N) the node's id before the change, or −1 for a node the change added.
  std::vector<std::int32_t> old_node;
};

/// What apply_topology_change() kept and rebuilt, for tests and reports.
struct TopologyChangeReport {
  std::size_t surviving_nodes{0};
  std::size_t added_nodes{0};
  std::size_t removed_nodes{0};
  bool pattern_changed{true};  ///< false: the system matrix and its factorisation were reused
};

/// The old→new node map of a change that keeps some of the nodes and removes the others
/// (`kept[i]`: node i survives), in their order: new node j is the j-th surviving old node.
[[nodiscard]] std::vector<std::int32_t> surviving_node_map(const std::vector<bool>& kept);

/// Replaces `model` by the changed body and maps `state` onto it, between steps. On an error
/// (the new config does not build, the map is malformed) both are left as they were. It
/// allocates; the haptic tick never calls it.
[[nodiscard]] Expected<TopologyChangeReport> apply_topology_change(MechanicalModel& model, MechanicalState& state,
                                                                   const TopologyChange& change);

}  // namespace hof::mechanics
