// Topology changes (src/hof/mechanics/topology_change.cpp): a beam under gravity loses its
// last layer of elements mid-run and keeps stepping; an unchanged mesh keeps the solver's
// workspace and the motion exactly; a malformed change leaves the body as it was. The
// incremental path (TopologyChange::old_tet) rebuilds only the elements a change adds and
// gives the body a full rebuild of the changed mesh gives: removals, repeated removals, every
// element around a node removed, a tetrahedron split by a node added at its centre.

#include <gtest/gtest.h>

#include "hof/mechanics/forces.h"
#include "hof/mechanics/step.h"
#include "hof/mechanics/topology_change.h"
#include "hof/mesh/tet_geometry.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;

constexpr double kDensity = 1000.0;
constexpr double kLength = 0.3;

// A cantilever of 6 cubes along x (6 tetrahedra each), held at x = 0, sagging under gravity.
ModelConfig beam(std::vector<Vec3> positions, std::vector<mesh::Tet> tets, LinearSolverKind linear,
                 FemMethod method = FemMethod::kLarge) {
  ModelConfig c;
  c.name = "beam";
  c.positions = std::move(positions);
  c.tets = std::move(tets);
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = kDensity;
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{2.0e6, 0.3, method, {}, {}};
  c.force_fields.push_back(fem);
  FixedConstraintConfig held;
  held.box = std::make_pair(Vec3(-1, -1, -1), Vec3(1e-9, 1, 1));
  c.fixed.push_back(held);
  c.ode.kind = OdeSolverKind::kEulerImplicit;
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.linear.kind = linear;
  c.linear.iterations = 50;
  c.dt_s = 0.005;
  return c;
}

ModelConfig whole_beam(LinearSolverKind linear, FemMethod method = FemMethod::kLarge) {
  const auto box = box_mesh(6, 1, 1, Vec3(kLength, 0.05, 0.05));
  return beam(box.nodes, box.tets, linear, method);
}

// The beam without its last layer of cubes (the elements beyond 5/6 of its length, and the
// nodes only they used), and where each remaining node was.
TopologyChange cut_last_layer(const ModelConfig& before) {
  const double cut = kLength * 5.0 / 6.0 + 1e-9;
  std::vector<mesh::Tet> kept_tets;
  std::vector<bool> used(before.positions.size(), false);
  for (const mesh::Tet& t : before.tets) {
    bool beyond = false;
    for (const mesh::NodeIndex i : t) beyond = beyond || before.positions[static_cast<std::size_t>(i)].x() > cut;
    if (beyond) continue;
    kept_tets.push_back(t);
    for (const mesh::NodeIndex i : t) used[static_cast<std::size_t>(i)] = true;
  }
  TopologyChange change;
  change.old_node = surviving_node_map(used);
  std::vector<std::int32_t> new_of_old(before.positions.size(), -1);
  std::vector<Vec3> positions;
  for (std::size_t j = 0; j < change.old_node.size(); ++j) {
    new_of_old[static_cast<std::size_t>(change.old_node[j])] = static_cast<std::int32_t>(j);
    positions.push_back(before.positions[static_cast<std::size_t>(change.old_node[j])]);
  }
  for (mesh::Tet& t : kept_tets) {
    for (mesh::NodeIndex& i : t) i = new_of_old[static_cast<std::size_t>(i)];
  }
  change.config = beam(std::move(positions), std::move(kept_tets), before.linear.kind);
  return change;
}

double tets_mass(const ModelConfig& c) {
  double v = 0.0;
  for (const mesh::Tet& t : c.tets) {
    const auto p = mesh::tet_corners(c.positions, t);
    v += std::abs(mesh::tet_signed_volume(p[0], p[1], p[2], p[3]));
  }
  return kDensity * v;
}

class TopologyChangeTest : public ::testing::TestWithParam<LinearSolverKind> {};

TEST_P(TopologyChangeTest, ABeamLosesItsLastLayerMidRunAndKeepsStepping) {
  const ModelConfig before = whole_beam(GetParam());
  auto model = build_model(before);
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  for (int i = 0; i < 40; ++i) ASSERT_TRUE(step(*model, state)) << state.divergence.reason;

  const TopologyChange change = cut_last_layer(before);
  const Eigen::VectorXd x_before = state.x, v_before = state.v;
  const std::int64_t steps_before = state.steps;
  auto report = apply_topology_change(*model, state, change);
  ASSERT_TRUE(report) << report.error().to_string();
  EXPECT_EQ(report->removed_nodes, 4u);  // the beam's free end face
  EXPECT_EQ(report->added_nodes, 0u);
  EXPECT_TRUE(report->pattern_changed);
  ASSERT_EQ(model->node_count(), before.positions.size() - 4);
  EXPECT_EQ(model->tets.size(), before.tets.size() - 6);

  // Surviving nodes keep their state; the mass is the remaining elements' mass.
  for (std::size_t j = 0; j < model->node_count(); ++j) {
    const auto o = 3 * static_cast<Eigen::Index>(change.old_node[j]);
    const auto k = 3 * static_cast<Eigen::Index>(j);
    EXPECT_EQ(state.x.segment<3>(k), x_before.segment<3>(o)) << "node " << j;
    EXPECT_EQ(state.v.segment<3>(k), v_before.segment<3>(o)) << "node " << j;
  }
  EXPECT_EQ(state.steps, steps_before);
  EXPECT_NEAR(model->total_mass_kg(), tets_mass(change.config), 1e-12 * tets_mass(change.config));
  EXPECT_NEAR(model->total_mass_kg(), 5.0 / 6.0 * tets_mass(before), 1e-12);

  // It keeps stepping: nothing non-finite, the shortened beam still sags and stays bounded.
  for (int i = 0; i < 200; ++i) {
    ASSERT_TRUE(step(*model, state)) << "step " << i << ": " << state.divergence.reason;
    ASSERT_TRUE(state.x.allFinite());
  }
  double lowest = 0.0;
  for (std::size_t j = 0; j < model->node_count(); ++j) {
    lowest = std::min(lowest, state.position(static_cast<std::int32_t>(j)).y() - model->rest_positions[j].y());
  }
  EXPECT_LT(lowest, -1e-5);
  EXPECT_GT(lowest, -0.05);
}

TEST_P(TopologyChangeTest, AnUnchangedMeshKeepsTheWorkspaceAndTheMotionExactly) {
  const ModelConfig config = whole_beam(GetParam());
  auto model = build_model(config);
  auto reference_model = build_model(config);
  ASSERT_TRUE(model && reference_model);
  MechanicalState state = make_state(*model);
  MechanicalState reference = make_state(*reference_model);
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(step(*model, state));
    ASSERT_TRUE(step(*reference_model, reference));
  }
  TopologyChange same;
  same.config = config;
  same.old_node = surviving_node_map(std::vector<bool>(config.positions.size(), true));
  auto report = apply_topology_change(*model, state, same);
  ASSERT_TRUE(report) << report.error().to_string();
  EXPECT_FALSE(report->pattern_changed);
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(step(*model, state));
    ASSERT_TRUE(step(*reference_model, reference));
  }
  EXPECT_EQ(state.x, reference.x);
  EXPECT_EQ(state.v, reference.v);
}

TEST_P(TopologyChangeTest, AMalformedChangeLeavesTheBodyAsItWas) {
  const ModelConfig config = whole_beam(GetParam());
  auto model = build_model(config);
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  ASSERT_TRUE(step(*model, state));
  const Eigen::VectorXd x = state.x;
  TopologyChange bad = cut_last_layer(config);
  bad.old_node[1] = bad.old_node[0];
  auto report = apply_topology_change(*model, state, bad);
  ASSERT_FALSE(report);
  EXPECT_NE(report.error().message.find("twice"), std::string::npos) << report.error().message;
  bad = cut_last_layer(config);
  bad.old_node.pop_back();
  EXPECT_FALSE(apply_topology_change(*model, state, bad));
  EXPECT_EQ(model->node_count(), config.positions.size());
  EXPECT_EQ(state.x, x);
  EXPECT_TRUE(step(*model, state));
}

INSTANTIATE_TEST_SUITE_P(Solvers, TopologyChangeTest,
                         ::testing::Values(LinearSolverKind::kConjugateGradient, LinearSolverKind::kSparseLdlt),
                         [](const auto& solver) {
                           return solver.param == LinearSolverKind::kSparseLdlt ? "Ldlt" : "Cg";
                         });

// ---- the incremental path --------------------------------------------------------------------

// |a − b| ≤ 1e-12 |b| (or absolutely tiny for a zero b).
::testing::AssertionResult near_relative(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " and " << b.size();
  const double difference = (a - b).norm();
  if (difference <= 1e-12 * std::max(b.norm(), 1e-300)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "relative difference " << difference / b.norm();
}

// Two bodies stepped alike; `incremental` takes a change through the incremental path,
// `whole` the same change rebuilt from its config. Afterwards both must be the same body.
struct IncrementalAgainstWhole {
  ModelConfig config;
  MechanicalModel incremental, whole;
  MechanicalState incremental_state, whole_state;

  explicit IncrementalAgainstWhole(ModelConfig c) : config(std::move(c)) {
    incremental = *build_model(config);
    whole = *build_model(config);
    incremental_state = make_state(incremental);
    whole_state = make_state(whole);
    // Under way: a sagging beam with some velocity, and a coupling input on the free end.
    incremental_state.external_force(incremental_state.external_force.size() - 2) = -3.0;
    whole_state.external_force = incremental_state.external_force;
    step_both(15);
  }

  void step_both(int steps) {
    for (int i = 0; i < steps; ++i) {
      ASSERT_TRUE(step(incremental, incremental_state)) << incremental_state.divergence.reason;
      ASSERT_TRUE(step(whole, whole_state)) << whole_state.divergence.reason;
    }
  }

  // Applies `change` both ways; returns the incremental report.
  TopologyChangeReport apply(const TopologyChange& change) {
    auto report = apply_topology_change(incremental, incremental_state, change);
    EXPECT_TRUE(report) << report.error().to_string();
    TopologyChange rebuilt = change;
    rebuilt.old_tet.clear();
    auto whole_report = apply_topology_change(whole, whole_state, rebuilt);
    EXPECT_TRUE(whole_report) << whole_report.error().to_string();
    EXPECT_TRUE(report->incremental);
    EXPECT_FALSE(whole_report->incremental);
    EXPECT_EQ(whole_report->elements_rebuilt, change.config.tets.size());
    EXPECT_EQ(report->surviving_nodes, whole_report->surviving_nodes);
    config = change.config;
    return *report;
  }

  // The same body: masses, supports, pattern, forces at the current state, then a few steps.
  void expect_same_body() {
    ASSERT_EQ(incremental.node_count(), whole.node_count());
    EXPECT_EQ(incremental.node_mass_kg, whole.node_mass_kg);
    EXPECT_EQ(incremental.fixed_dofs, whole.fixed_dofs);
    EXPECT_EQ(incremental.pattern.row_start(), whole.pattern.row_start());
    EXPECT_EQ(incremental.pattern.columns(), whole.pattern.columns());
    EXPECT_EQ(incremental_state.x, whole_state.x);
    EXPECT_EQ(incremental_state.v, whole_state.v);
    Eigen::VectorXd f_incremental(incremental_state.x.size()), f_whole(whole_state.x.size());
    compute_forces(incremental, incremental_state, incremental_state.x, incremental_state.v, f_incremental);
    compute_forces(whole, whole_state, whole_state.x, whole_state.v, f_whole);
    EXPECT_TRUE(near_relative(f_incremental, f_whole));
    step_both(5);
    EXPECT_TRUE(near_relative(incremental_state.x, whole_state.x));
    EXPECT_TRUE(near_relative(incremental_state.v, whole_state.v));
  }
};

// The ids of the tetrahedra that use `node`.
std::vector<std::int32_t> tets_around(const ModelConfig& c, mesh::NodeIndex node) {
  std::vector<std::int32_t> ids;
  for (std::size_t t = 0; t < c.tets.size(); ++t) {
    if (std::find(c.tets[t].begin(), c.tets[t].end(), node) != c.tets[t].end())
      ids.push_back(static_cast<std::int32_t>(t));
  }
  return ids;
}

struct IncrementalCase {
  LinearSolverKind linear;
  FemMethod method;
};

class IncrementalTopologyChangeTest : public ::testing::TestWithParam<IncrementalCase> {};

TEST_P(IncrementalTopologyChangeTest, RemovingTetrahedraRebuildsNoElementAndEqualsAFullRebuild) {
  IncrementalAgainstWhole bodies(whole_beam(GetParam().linear, GetParam().method));
  const std::size_t before = bodies.config.tets.size();
  const TopologyChange change = tetrahedra_change(bodies.config, {30, 31, 32});
  const TopologyChangeReport report = bodies.apply(change);
  EXPECT_EQ(report.elements_rebuilt, 0u);  // removal: every remaining element keeps its data
  EXPECT_EQ(report.added_nodes, 0u);
  EXPECT_GT(report.nodes_remassed, 0u);
  EXPECT_LT(report.nodes_remassed, bodies.incremental.node_count());
  EXPECT_EQ(bodies.incremental.tets.size(), before - 3);
  bodies.expect_same_body();
}

TEST_P(IncrementalTopologyChangeTest, RepeatedRemovalsStayEqualToAFullRebuild) {
  IncrementalAgainstWhole bodies(whole_beam(GetParam().linear, GetParam().method));
  for (const std::int32_t first : {33, 20, 7}) {
    const TopologyChangeReport report = bodies.apply(tetrahedra_change(bodies.config, {first, first + 1}));
    EXPECT_EQ(report.elements_rebuilt, 0u);
    bodies.expect_same_body();
  }
}

TEST_P(IncrementalTopologyChangeTest, RemovingEverythingAroundANodeRemovesTheNode) {
  IncrementalAgainstWhole bodies(whole_beam(GetParam().linear, GetParam().method));
  // A corner of the free end: the nodes are numbered x fastest (box_mesh), so node 6 is at x = L.
  const mesh::NodeIndex corner = 6;
  ASSERT_NEAR(bodies.config.positions[corner].x(), kLength, 1e-12);
  const std::size_t nodes = bodies.config.positions.size();
  const TopologyChange change = tetrahedra_change(bodies.config, tets_around(bodies.config, corner));
  const TopologyChangeReport report = bodies.apply(change);
  EXPECT_EQ(report.removed_nodes, 1u);
  EXPECT_EQ(bodies.incremental.node_count(), nodes - 1);
  EXPECT_EQ(std::count(change.old_node.begin(), change.old_node.end(), corner), 0);
  EXPECT_EQ(report.elements_rebuilt, 0u);
  bodies.expect_same_body();
}

TEST_P(IncrementalTopologyChangeTest, SplittingATetrahedronAtAnAddedNodeRebuildsOnlyItsPieces) {
  IncrementalAgainstWhole bodies(whole_beam(GetParam().linear, GetParam().method));
  const std::size_t nodes = bodies.config.positions.size();
  for (const std::int32_t split : {25, 12}) {  // two splits in a row, the second on the changed body
    const mesh::Tet t = bodies.config.tets[static_cast<std::size_t>(split)];
    const auto p = mesh::tet_corners(bodies.config.positions, t);
    const Vec3 centre = 0.25 * (p[0] + p[1] + p[2] + p[3]);
    const auto added = static_cast<mesh::NodeIndex>(bodies.config.positions.size());
    const std::vector<mesh::Tet> pieces{
        {added, t[1], t[2], t[3]}, {t[0], added, t[2], t[3]}, {t[0], t[1], added, t[3]}, {t[0], t[1], t[2], added}};
    const TopologyChange change = tetrahedra_change(bodies.config, {split}, {centre}, pieces);
    const TopologyChangeReport report = bodies.apply(change);
    EXPECT_EQ(report.added_nodes, 1u);
    EXPECT_EQ(report.removed_nodes, 0u);
    EXPECT_EQ(report.elements_rebuilt, pieces.size());  // only the split's pieces
    EXPECT_EQ(report.nodes_remassed, 5u);               // the split tetrahedron's corners and its centre
    bodies.expect_same_body();
  }
  EXPECT_EQ(bodies.incremental.node_count(), nodes + 2);
}

TEST(IncrementalTopologyChange, ABodyTheIncrementalPathDoesNotKnowIsRebuiltWhole) {
  ModelConfig c = whole_beam(LinearSolverKind::kConjugateGradient);
  c.force_fields.front().tetrahedron_fem->element_poisson_ratio.assign(c.tets.size(), 0.3);  // a split field
  auto model = build_model(c);
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  auto report = apply_topology_change(*model, state, tetrahedra_change(c, {0}));
  ASSERT_TRUE(report) << report.error().to_string();
  EXPECT_FALSE(report->incremental);
  EXPECT_EQ(report->elements_rebuilt, c.tets.size() - 1);
}

TEST(IncrementalTopologyChange, TrianglesAndSpringsGoWithTheRemovedNodesThroughTheFullRebuild) {
  ModelConfig c = whole_beam(LinearSolverKind::kConjugateGradient);
  c.triangles = {{6, 5, 13}, {0, 1, 7}};  // one on the end corner that goes, one on the held end
  ForceFieldConfig springs;
  springs.name = "springs";
  springs.mesh_springs = MeshSpringConfig{};
  springs.mesh_springs->stiffness_n_per_m = 100.0;
  c.force_fields.push_back(springs);
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  ASSERT_TRUE(step(*model, state));
  const TopologyChange change = tetrahedra_change(c, tets_around(c, 6));
  ASSERT_EQ(change.config.triangles.size(), 1u);
  EXPECT_EQ(change.config.triangles[0], (mesh::Tri{0, 1, 6}));  // renumbered: node 7 follows the removed 6
  auto report = apply_topology_change(*model, state, change);
  ASSERT_TRUE(report) << report.error().to_string();
  EXPECT_FALSE(report->incremental);  // springs are not on the incremental path yet
  EXPECT_EQ(model->triangles.size(), 1u);
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
}

INSTANTIATE_TEST_SUITE_P(SolversAndMethods, IncrementalTopologyChangeTest,
                         ::testing::Values(IncrementalCase{LinearSolverKind::kConjugateGradient, FemMethod::kLarge},
                                           IncrementalCase{LinearSolverKind::kSparseLdlt, FemMethod::kLarge},
                                           IncrementalCase{LinearSolverKind::kConjugateGradient, FemMethod::kSmall},
                                           IncrementalCase{LinearSolverKind::kSparseLdlt, FemMethod::kPolar}),
                         [](const auto& test) {
                           const char* method = test.param.method == FemMethod::kSmall   ? "Small"
                                                : test.param.method == FemMethod::kLarge ? "Large"
                                                                                         : "Polar";
                           return std::string(test.param.linear == LinearSolverKind::kSparseLdlt ? "Ldlt" : "Cg") +
                                  method;
                         });

}  // namespace
}  // namespace hof::mechanics
