// Topology changes (src/hof/mechanics/topology_change.cpp): a beam under gravity loses its
// last layer of elements mid-run and keeps stepping; an unchanged mesh keeps the solver's
// workspace and the motion exactly; a malformed change leaves the body as it was.

#include <gtest/gtest.h>

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
ModelConfig beam(std::vector<Vec3> positions, std::vector<mesh::Tet> tets, LinearSolverKind linear) {
  ModelConfig c;
  c.name = "beam";
  c.positions = std::move(positions);
  c.tets = std::move(tets);
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = kDensity;
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{2.0e6, 0.3, FemMethod::kLarge, {}, {}};
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

ModelConfig whole_beam(LinearSolverKind linear) {
  const auto box = box_mesh(6, 1, 1, Vec3(kLength, 0.05, 0.05));
  return beam(box.nodes, box.tets, linear);
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
                         [](const auto& solver) { return solver.param == LinearSolverKind::kSparseLdlt ? "Ldlt" : "Cg"; });

}  // namespace
}  // namespace hof::mechanics
