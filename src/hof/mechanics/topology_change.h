#pragma once
/// @file
/// The seam for changes of a body's topology while it runs (cutting, tearing, refinement):
/// elements removed or split, nodes added. A change is the body after it (its ModelConfig:
/// rest positions, elements, materials, supports) and where each of its nodes was before.
/// apply_topology_change() swaps the model for the changed one and carries the motion over:
/// surviving nodes keep their positions, velocities and coupling input; added nodes start at
/// their rest position, at rest. When the change also says where each tetrahedron was
/// (`old_tet`) and the body is one the incremental path knows (tetrahedral FEM, lumped or
/// uniform mass), only what the change touched is rebuilt: the new elements' rest data and
/// the masses of the nodes they or the removed ones touch; every other element keeps its
/// precomputed data. Otherwise the model is rebuilt from the config. What each path rebuilds
/// is listed in docs/architecture.md ("Topology changes").

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
  /// Empty (the whole model is rebuilt), or (new tets) the tetrahedron's id before the change,
  /// −1 for one the change added (a split's pieces). A kept tetrahedron has the same corners,
  /// in the same order, renumbered by old_node, and the same material.
  std::vector<std::int32_t> old_tet;
};

/// What apply_topology_change() kept and rebuilt, for tests and reports.
struct TopologyChangeReport {
  std::size_t surviving_nodes{0};
  std::size_t added_nodes{0};
  std::size_t removed_nodes{0};
  bool pattern_changed{true};  ///< false: the system matrix and its factorisation were reused
  /// True: only what the change touched was rebuilt (TopologyChange::old_tet); false: the
  /// whole model was built from the config.
  bool incremental{false};
  /// Elements whose rest data (gradients, volumes, frames) was computed: the added ones on the
  /// incremental path, every element of every field on a full rebuild.
  std::size_t elements_rebuilt{0};
  std::size_t nodes_remassed{0};  ///< nodes whose lumped mass was summed anew (incremental path)
};

/// The topology change that removes the tetrahedra `removed` (ids in config.tets) from the
/// body `before`, with the nodes only they used, and adds `added_nodes` (rest positions) and
/// `added_tets` (over the nodes before the change, and node N + k for added node k, N the node
/// count before): config, old_node and old_tet filled, so that apply_topology_change can take
/// the incremental path. Per-element lists of the config (moduli, densities, regions) follow
/// the kept elements; an added element gets the config's default (0 in the lists). Fixed
/// constraints given by index are renumbered (a removed node's is dropped).
[[nodiscard]] TopologyChange tetrahedra_change(const ModelConfig& before, const std::vector<std::int32_t>& removed,
                                               const std::vector<Vec3>& added_nodes = {},
                                               const std::vector<mesh::Tet>& added_tets = {});

/// The old→new node map of a change that keeps some of the nodes and removes the others
/// (`kept[i]`: node i survives), in their order: new node j is the j-th surviving old node.
[[nodiscard]] std::vector<std::int32_t> surviving_node_map(const std::vector<bool>& kept);

/// Replaces `model` by the changed body and maps `state` onto it, between steps. On an error
/// (the new config does not build, the map is malformed) both are left as they were. It
/// allocates; the haptic tick never calls it.
[[nodiscard]] Expected<TopologyChangeReport> apply_topology_change(MechanicalModel& model, MechanicalState& state,
                                                                   const TopologyChange& change);

}  // namespace hof::mechanics
