// The force stage (src/hof/mechanics/forces.cpp): what compute_forces adds up, the fixed
// degrees of freedom it clears, the local reaction at a patch and the residual force.

#include <gtest/gtest.h>

#include <array>

#include "hof/mechanics/forces.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;

ModelConfig block(bool fixed_base) {
  const auto box = box_mesh(2, 2, 2, Vec3(0.1, 0.1, 0.1));
  ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.gravity_m_per_s2 = Vec3(0.0, -9.81, 0.0);
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{10000.0, 0.3, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  if (fixed_base) {
    FixedConstraintConfig base;
    base.box = std::make_pair(Vec3(-1, -1, -1), Vec3(1, 1e-9, 1));
    c.fixed.push_back(base);
  }
  return c;
}

TEST(Forces, AtRestTheyAreGravityPlusTheCouplingInput) {
  auto model = build_model(block(false));
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  state.external_force[3 * 5 + 2] = 0.25;
  compute_forces(*model, state, state.x, state.v, state.f);
  for (std::size_t i = 0; i < model->node_count(); ++i) {
    Vec3 expected = model->node_mass_kg[i] * model->gravity_m_per_s2;
    if (i == 5) expected.z() += 0.25;
    EXPECT_LT((state.f.segment<3>(3 * static_cast<Eigen::Index>(i)) - expected).norm(), 1e-12) << "node " << i;
  }
}

TEST(Forces, FixedDegreesOfFreedomCarryNoForce) {
  auto model = build_model(block(true));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  compute_forces(*model, state, state.x, state.v, state.f);
  ASSERT_FALSE(model->fixed_dofs.empty());
  for (const std::int32_t d : model->fixed_dofs) EXPECT_EQ(state.f[d], 0.0);
}

TEST(Forces, ElasticForceAtAPatchIsTheFieldsForceSummedOverItsNodes) {
  auto model = build_model(block(false));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  for (Eigen::Index k = 0; k < state.x.size(); ++k) state.x[k] *= 1.0 + 0.01 * static_cast<double>(k % 7);
  const std::array<std::int32_t, 3> nodes{4, 13, 22};
  const std::array<double, 3> weights{0.2, 0.5, 0.3};
  const Vec3 local = point_elastic_force(*model, state, nodes, weights);
  // The same sum from a whole pass of the force field.
  Eigen::VectorXd f = Eigen::VectorXd::Zero(state.x.size());
  model->force_fields[0]->add_force(state.x, state.v, state.field_states[0], f);
  Vec3 whole = Vec3::Zero();
  for (const std::int32_t n : nodes) whole += f.segment<3>(3 * static_cast<Eigen::Index>(n));
  EXPECT_GT(whole.norm(), 0.0);
  EXPECT_LT((local - whole).norm(), 1e-9 * whole.norm());
}

TEST(Forces, ResidualAtRestUnderGravityIsTheLargestWeight) {
  auto model = build_model(block(false));
  ASSERT_TRUE(model);
  MechanicalState state = make_state(*model);
  double heaviest = 0.0;
  for (const double m : model->node_mass_kg) heaviest = std::max(heaviest, m);
  EXPECT_NEAR(max_residual_force(*model, state), heaviest * 9.81, 1e-12);
}

}  // namespace
}  // namespace hof::mechanics
