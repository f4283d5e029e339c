// Mesh springs (SOFA's MeshSpringForceField): the stiffness and damping each spring gets, by
// SOFA's rule (per unit strain: k/l0 and c/l0, MeshSpringForceField::addSpring) or the same
// for every spring (HoF's own surface springs), and which element kind's values an edge
// shared by a triangle and a tetrahedron takes (MeshSpringForceField::init: the first kind).

#include "hof/mechanics/detail/mesh_spring_force_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "hof/mechanics/block_sparse_matrix.h"

namespace hof::mechanics {
namespace {

// The right triangle with legs 3 and 4 m (hypotenuse 5 m): three springs of three lengths.
const std::vector<Vec3> kTriangleNodes = {Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 4, 0)};
const std::vector<mesh::Tri> kTriangle = {{0, 1, 2}};

Eigen::VectorXd stacked(const std::vector<Vec3>& points) {
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(points.size()));
  for (std::size_t n = 0; n < points.size(); ++n) x.segment<3>(3 * static_cast<Eigen::Index>(n)) = points[n];
  return x;
}

Eigen::VectorXd forces(const MeshSpringForceField& field, const Eigen::VectorXd& x, const Eigen::VectorXd& v) {
  ForceFieldState state = field.make_state();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  field.add_force(x, v, state, f);
  return f;
}

TEST(MeshSprings, SofasRuleDividesStiffnessAndDampingByTheRestLength) {
  MeshSpringConfig config{6.0, 2.0, 1.0, SpringStiffnessRule::kDividedByRestLength};
  auto field = MeshSpringForceField::make(kTriangleNodes, {}, kTriangle, config, "springs");
  ASSERT_TRUE(field) << field.error().to_string();
  ASSERT_EQ((*field)->spring_count(), 3u);
  for (std::size_t s = 0; s < 3; ++s) {
    const auto spring = (*field)->spring(s);
    const double length = (kTriangleNodes[spring.nodes[1]] - kTriangleNodes[spring.nodes[0]]).norm();
    EXPECT_DOUBLE_EQ(spring.rest_length_m, length);
    EXPECT_DOUBLE_EQ(spring.stiffness_n_per_m, 6.0 / length) << "spring " << s;
    EXPECT_DOUBLE_EQ(spring.damping_n_s_per_m, 2.0 / length) << "spring " << s;
  }
  // A uniform stretch by ε strains every spring by ε: per unit strain, each pulls with the
  // same tension kε whatever its length. Node 0 (the right angle) feels kε along each leg.
  const double strain = 1e-3;
  std::vector<Vec3> stretched;
  for (const Vec3& p : kTriangleNodes) stretched.push_back((1.0 + strain) * p);
  const Eigen::VectorXd rest_velocity = Eigen::VectorXd::Zero(9);
  Eigen::VectorXd f = forces(**field, stacked(stretched), rest_velocity);
  EXPECT_NEAR(f(0), 6.0 * strain, 1e-12);
  EXPECT_NEAR(f(1), 6.0 * strain, 1e-12);
  // The same for the dampers under a uniform rate of strain: c ε̇ along each leg.
  const double rate = 0.5;
  Eigen::VectorXd v(9);
  for (std::size_t n = 0; n < 3; ++n) v.segment<3>(3 * static_cast<Eigen::Index>(n)) = rate * kTriangleNodes[n];
  f = forces(**field, stacked(kTriangleNodes), v);
  EXPECT_NEAR(f(0), 2.0 * rate, 1e-12);
  EXPECT_NEAR(f(1), 2.0 * rate, 1e-12);
  // The energy is that of the springs' own stiffness: ½ Σ (k/l)(εl)² = ½ k ε² Σ l.
  EXPECT_NEAR((*field)->potential_energy(stacked(stretched), ForceFieldState{}), 0.5 * 6.0 * strain * strain * 12.0,
              1e-15);
}

TEST(MeshSprings, HofsOwnRuleGivesEverySpringTheSameValues) {
  auto field = MeshSpringForceField::make(kTriangleNodes, {}, kTriangle, MeshSpringConfig{6.0, 2.0, 1.0}, "springs");
  ASSERT_TRUE(field) << field.error().to_string();
  for (std::size_t s = 0; s < 3; ++s) {
    EXPECT_EQ((*field)->spring(s).stiffness_n_per_m, 6.0);
    EXPECT_EQ((*field)->spring(s).damping_n_s_per_m, 2.0);
  }
  // The uniform stretch now pulls each spring with k ε l: 3kε and 4kε on node 0's legs.
  const double strain = 1e-3;
  std::vector<Vec3> stretched;
  for (const Vec3& p : kTriangleNodes) stretched.push_back((1.0 + strain) * p);
  const Eigen::VectorXd f = forces(**field, stacked(stretched), Eigen::VectorXd::Zero(9));
  EXPECT_NEAR(f(0), 3.0 * 6.0 * strain, 1e-12);
  EXPECT_NEAR(f(1), 4.0 * 6.0 * strain, 1e-12);
}

// The matrix −∂f/∂x the springs add at x (zero velocity unless given).
Eigen::MatrixXd stiffness_at(MeshSpringForceField& field, const Eigen::VectorXd& x, const Eigen::VectorXd& v) {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  field.collect_couplings(pairs);
  BlockSparseMatrix k = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(x.size() / 3), pairs);
  field.bind(k);
  ForceFieldState state = field.make_state();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  field.add_force(x, v, state, f);
  k.set_zero();
  field.add_stiffness(state, 1.0, k);
  return k.to_dense();
}

// SOFA's tangent (SpringForceField::computeSpringForce) is the exact −∂f/∂x, also for a
// compressed spring, whose transverse stiffness f/l is negative; HoF's own clamps it at 0.
TEST(MeshSprings, SofasTangentIsTheExactDerivativeOfACompressedMesh) {
  std::vector<Vec3> squeezed;
  for (const Vec3& p : kTriangleNodes) squeezed.push_back(Vec3(0.8 * p.x(), 0.9 * p.y(), 0.0));
  const Eigen::VectorXd x = stacked(squeezed);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(9);
  MeshSpringConfig config{6.0, 2.0, 1.0, SpringStiffnessRule::kDividedByRestLength, SpringTangent::kExact};
  auto exact = MeshSpringForceField::make(kTriangleNodes, {}, kTriangle, config, "springs");
  config.tangent = SpringTangent::kClampedTransverse;
  auto clamped = MeshSpringForceField::make(kTriangleNodes, {}, kTriangle, config, "springs");
  ASSERT_TRUE(exact && clamped);
  Eigen::MatrixXd difference(9, 9);
  const double h = 1e-6;
  for (Eigen::Index j = 0; j < 9; ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    difference.col(j) = -(forces(**exact, plus, still) - forces(**exact, minus, still)) / (2.0 * h);
  }
  const Eigen::MatrixXd k_exact = stiffness_at(**exact, x, still);
  EXPECT_LT((k_exact - difference).norm(), 1e-6 * difference.norm()) << k_exact << "\n\n" << difference;
  EXPECT_GT((stiffness_at(**clamped, x, still) - difference).norm(), 1e-2 * difference.norm());
  // The damper's tension is in SOFA's f/l too: a closing rate adds (c ε̇) / l transversally.
  Eigen::VectorXd closing(9);
  for (std::size_t n = 0; n < 3; ++n) closing.segment<3>(3 * static_cast<Eigen::Index>(n)) = -0.5 * squeezed[n];
  const Eigen::MatrixXd k_moving = stiffness_at(**exact, x, closing);
  // Spring 0-1 lies along x: its transverse (y) stiffness on node 0 changes by c ε̇ / l, with
  // c = 2/3 N·s/m (2 per unit strain over the 3 m rest length), ε̇ l the closing rate 0.5·2.4 m/s
  // over its length 2.4 m; spring 0-2 along y does not act in y transversally.
  EXPECT_NEAR(k_moving(1, 4) - k_exact(1, 4), -(-(2.0 / 3.0) * 0.5 * 2.4 / 2.4), 1e-9);
}

// One tetrahedron whose face (0, 1, 2) is also a surface triangle.
const std::vector<Vec3> kTetNodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 3)};
const std::vector<mesh::Tet> kTet = {{0, 1, 2, 3}};
const std::vector<mesh::Tri> kFace = {{0, 1, 2}};

std::map<std::pair<int, int>, double> stiffness_by_edge(const MeshSpringForceField& field) {
  std::map<std::pair<int, int>, double> out;
  for (std::size_t s = 0; s < field.spring_count(); ++s) {
    const auto spring = field.spring(s);
    out[{spring.nodes[0], spring.nodes[1]}] = spring.stiffness_n_per_m * spring.rest_length_m;
  }
  return out;
}

TEST(MeshSprings, AnEdgeOfATriangleAndATetrahedronTakesTheTrianglesValues) {
  MeshSpringConfig config{0.0, 0.0, 1.0, SpringStiffnessRule::kDividedByRestLength};
  config.triangles = SpringValues{10.0, 0.0};
  config.tetrahedra = SpringValues{1.0, 0.0};
  auto field = MeshSpringForceField::make(kTetNodes, kTet, kFace, config, "springs");
  ASSERT_TRUE(field) << field.error().to_string();
  ASSERT_EQ((*field)->spring_count(), 6u);  // one spring per edge, never two
  const auto k = stiffness_by_edge(**field);
  for (const auto& edge : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) EXPECT_NEAR(k.at(edge), 10.0, 1e-12);
  for (const auto& edge : {std::pair{0, 3}, std::pair{1, 3}, std::pair{2, 3}}) EXPECT_NEAR(k.at(edge), 1.0, 1e-12);

  // A kind with no stiffness and no damping adds no springs: its edges take the next kind's.
  config.triangles = SpringValues{0.0, 0.0};
  field = MeshSpringForceField::make(kTetNodes, kTet, kFace, config, "springs");
  ASSERT_TRUE(field) << field.error().to_string();
  ASSERT_EQ((*field)->spring_count(), 6u);
  for (const auto& [edge, value] : stiffness_by_edge(**field))
    EXPECT_NEAR(value, 1.0, 1e-12) << edge.first << "-" << edge.second;

  // SOFA's `stiffness` is every kind's: all six edges alike.
  auto generic = MeshSpringForceField::make(
      kTetNodes, kTet, kFace, MeshSpringConfig{4.0, 0.0, 1.0, SpringStiffnessRule::kDividedByRestLength}, "springs");
  ASSERT_TRUE(generic) << generic.error().to_string();
  for (const auto& [edge, value] : stiffness_by_edge(**generic)) EXPECT_NEAR(value, 4.0, 1e-12);
}

TEST(MeshSprings, ABadValueOfAKindIsNamed) {
  MeshSpringConfig config{1.0, 0.0};
  config.tetrahedra = SpringValues{-2.0, 0.0};
  auto field = MeshSpringForceField::make(kTetNodes, kTet, {}, config, "springs");
  ASSERT_FALSE(field);
  EXPECT_NE(field.error().message.find("tetrahedraStiffness must be >= 0, got -2"), std::string::npos)
      << field.error().message;
}

}  // namespace
}  // namespace hof::mechanics
