// The body's compliance at a point (point_compliance.h): against the static displacement
// under a load at that point (linear FEM: the response is exactly linear), symmetric and
// positive definite, the weighted point of two nodes as linearity gives it, and a body that
// is not held refused.

#include "hof/mechanics/point_compliance.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <array>

#include "hof/mechanics/step.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;
using testing::BoxMesh;

// A small-strain FEM block held at x = 0 (every direction); `loads`: constant forces at nodes.
ModelConfig held_block(const BoxMesh& box, const std::vector<std::pair<std::int32_t, Vec3>>& loads = {}) {
  ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = MassKind::kUniform;
  c.gravity_m_per_s2 = Vec3::Zero();
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{3000.0, 0.3, FemMethod::kSmall, {}, {}};
  c.force_fields.push_back(fem);
  FixedConstraintConfig held;
  for (std::size_t i = 0; i < box.nodes.size(); ++i) {
    if (box.nodes[i].x() == 0.0) held.indices.push_back(static_cast<std::int32_t>(i));
  }
  c.fixed.push_back(held);
  if (!loads.empty()) {
    ForceFieldConfig load;
    load.name = "load";
    load.constant_force = ConstantForceConfig{};
    for (const auto& [node, force] : loads) {
      load.constant_force->indices.push_back(node);
      load.constant_force->forces.push_back(force);
    }
    c.force_fields.push_back(load);
  }
  c.ode.kind = OdeSolverKind::kStatic;
  c.ode.newton_iterations = 5;
  c.ode.newton_residual_tolerance_n = 1e-13;
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  return c;
}

// The static displacement of the held block under `loads`, at each node of `nodes`.
std::vector<Vec3> static_displacement(const BoxMesh& box, const std::vector<std::pair<std::int32_t, Vec3>>& loads,
                                      const std::vector<std::int32_t>& nodes) {
  auto model = build_model(held_block(box, loads));
  EXPECT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  EXPECT_TRUE(step(*model, state)) << state.divergence.reason;
  std::vector<Vec3> u;
  for (const std::int32_t n : nodes) u.push_back(state.position(n) - box.nodes[static_cast<std::size_t>(n)]);
  return u;
}

// Compliance at the free corner: C·F is the displacement a static solve gives under F there.
TEST(PointCompliance, IsTheStaticDisplacementPerNewtonAtTheNode) {
  const BoxMesh box = box_mesh(3, 2, 2, Vec3(0.3, 0.1, 0.1));
  const std::int32_t corner = box.index(3, 2, 2);
  auto model = build_model(held_block(box));
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  const std::array<std::int32_t, 1> nodes{corner};
  const std::array<double, 1> weights{1.0};
  Mat3 compliance = Mat3::Zero();
  ASSERT_TRUE(compute_point_compliance(*model, state, nodes, weights, compliance));

  const Vec3 force(0.01, 0.02, -0.03);
  const Vec3 u = static_displacement(box, {{corner, force}}, {corner})[0];
  ASSERT_GT(u.norm(), 1e-6) << "the load must move the corner";
  EXPECT_LT((compliance * force - u).norm(), 1e-6 * u.norm());
  // A compliance (the inverse of a symmetric stiffness block's Schur complement) is symmetric
  // and positive definite; the bar is softest across its length (bending), stiffest along it.
  EXPECT_LT((compliance - compliance.transpose()).norm(), 1e-8 * compliance.norm());
  const Eigen::SelfAdjointEigenSolver<Mat3> eigen(0.5 * (compliance + compliance.transpose()));
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
  EXPECT_LT(compliance(0, 0), compliance(1, 1));
  EXPECT_LT(compliance(0, 0), compliance(2, 2));
}

// The point half-way between two nodes: by linearity, the mean displacement of the two when
// F/2 acts at each.
TEST(PointCompliance, AWeightedPointIsTheWeightedResponseOfItsNodes) {
  const BoxMesh box = box_mesh(3, 2, 2, Vec3(0.3, 0.1, 0.1));
  const std::int32_t a = box.index(3, 2, 2), b = box.index(3, 0, 1);
  auto model = build_model(held_block(box));
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  const std::array<std::int32_t, 2> nodes{a, b};
  const std::array<double, 2> weights{0.5, 0.5};
  Mat3 compliance = Mat3::Zero();
  ASSERT_TRUE(compute_point_compliance(*model, state, nodes, weights, compliance));
  const Vec3 force(-0.02, 0.01, 0.04);
  const std::vector<Vec3> u = static_displacement(box, {{a, 0.5 * force}, {b, 0.5 * force}}, {a, b});
  const Vec3 mean = 0.5 * (u[0] + u[1]);
  EXPECT_LT((compliance * force - mean).norm(), 1e-6 * mean.norm());
}

TEST(PointCompliance, ABodyThatIsNotHeldHasNone) {
  const BoxMesh box = box_mesh(2, 1, 1, Vec3(0.2, 0.1, 0.1));
  ModelConfig c = held_block(box);
  c.fixed.clear();
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  const std::array<std::int32_t, 1> nodes{box.index(2, 1, 1)};
  const std::array<double, 1> weights{1.0};
  Mat3 compliance = Mat3::Zero();
  EXPECT_FALSE(compute_point_compliance(*model, state, nodes, weights, compliance, 200))
      << "a free body has a rigid motion: no finite compliance";
}

}  // namespace
}  // namespace hof::mechanics
