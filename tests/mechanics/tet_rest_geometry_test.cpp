// The rest geometry every tetrahedral force field precomputes (detail/tet_rest_geometry.cpp):
// volume, shape-function gradients (against the definition b_i·(x_j − x_0) = δ_ij), the
// reordering of an element inverted at rest, the errors, and the per-element modulus weights.

#include "hof/mechanics/detail/tet_rest_geometry.h"

#include <gtest/gtest.h>

#include <vector>

namespace hof::mechanics {
namespace {

// A right tetrahedron of 2 cm legs, sheared so that no gradient is axis-aligned.
std::vector<Vec3> sheared_tet() {
  return {Vec3(0.01, 0.02, 0.0), Vec3(0.03, 0.021, 0.001), Vec3(0.012, 0.04, 0.002), Vec3(0.011, 0.023, 0.02)};
}

TEST(TetRestGeometry, VolumeIsTheTripleProductOverSix) {
  const auto p = sheared_tet();
  const auto g = tet_rest_geometry(p, mesh::Tet{0, 1, 2, 3}, 0, "FEM");
  ASSERT_TRUE(g) << g.error().message;
  const double expected = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) / 6.0;
  ASSERT_GT(expected, 0.0);
  EXPECT_NEAR(g->volume, expected, 1e-15 * expected + 1e-22);
}

TEST(TetRestGeometry, GradientsAreTheShapeFunctionGradientsAndSumToZero) {
  const auto p = sheared_tet();
  const auto g = tet_rest_geometry(p, mesh::Tet{0, 1, 2, 3}, 0, "FEM");
  ASSERT_TRUE(g);
  for (int i = 1; i <= 3; ++i) {
    for (int j = 1; j <= 3; ++j) {
      EXPECT_NEAR(g->gradients[i].dot(p[g->nodes[j]] - p[g->nodes[0]]), i == j ? 1.0 : 0.0, 1e-12) << i << "," << j;
    }
  }
  EXPECT_LT((g->gradients[0] + g->gradients[1] + g->gradients[2] + g->gradients[3]).norm(), 1e-9);
}

TEST(TetRestGeometry, DeformationGradientOfAnAffineMapIsItsMatrix) {
  const auto p = sheared_tet();
  const auto g = tet_rest_geometry(p, mesh::Tet{0, 1, 2, 3}, 0, "FEM");
  ASSERT_TRUE(g);
  Mat3 a;
  a << 1.1, 0.2, -0.05, 0.03, 0.9, 0.1, -0.2, 0.04, 1.3;
  const Vec3 c(0.5, -0.2, 0.1);
  Eigen::VectorXd x(12);
  for (int n = 0; n < 4; ++n) x.segment<3>(3 * n) = a * p[static_cast<std::size_t>(n)] + c;
  EXPECT_LT((deformation_gradient(*g, x) - a).norm(), 1e-12);
}

TEST(TetRestGeometry, AnElementInvertedAtRestIsReorderedToAPositiveVolume) {
  const auto p = sheared_tet();
  const auto upright = tet_rest_geometry(p, mesh::Tet{0, 1, 2, 3}, 0, "FEM");
  const auto inverted = tet_rest_geometry(p, mesh::Tet{0, 1, 3, 2}, 0, "FEM");
  ASSERT_TRUE(upright && inverted);
  EXPECT_EQ(inverted->nodes, (std::array<std::int32_t, 4>{0, 1, 2, 3}));
  EXPECT_NEAR(inverted->volume, upright->volume, 1e-20);
}

TEST(TetRestGeometry, ANodeOutOfRangeOrAFlatElementIsAnErrorNamingTheFieldAndElement) {
  auto p = sheared_tet();
  auto out_of_range = tet_rest_geometry(p, mesh::Tet{0, 1, 2, 7}, 12, "TetrahedronFEMForceField 'FEM'");
  ASSERT_FALSE(out_of_range);
  EXPECT_NE(out_of_range.error().message.find("TetrahedronFEMForceField 'FEM': tetrahedron 12 refers to node 7 of 4"),
            std::string::npos)
      << out_of_range.error().message;
  p[3] = 0.5 * (p[1] + p[2]);  // coplanar with the other three
  auto flat = tet_rest_geometry(p, mesh::Tet{0, 1, 2, 3}, 3, "FEM");
  ASSERT_FALSE(flat);
  EXPECT_NE(flat.error().message.find("tetrahedron 3 (nodes 0 1 2 3) is degenerate"), std::string::npos)
      << flat.error().message;
}

TEST(ElementModulusWeights, AreEachElementsModulusOverTheFieldsWithZeroMeaningTheFieldsOwn) {
  const auto w = element_modulus_weights({2000.0, 0.0, 500.0}, 1000.0, 3, "FEM");
  ASSERT_TRUE(w);
  EXPECT_EQ(*w, (std::vector<double>{2.0, 1.0, 0.5}));
  const auto none = element_modulus_weights({}, 1000.0, 2, "FEM");
  ASSERT_TRUE(none);
  EXPECT_EQ(*none, (std::vector<double>{1.0, 1.0}));
}

TEST(ElementModulusWeights, AWrongLengthOrANegativeOrNonFiniteValueIsRefused) {
  const auto short_list = element_modulus_weights({1.0, 2.0}, 1000.0, 3, "FEM");
  ASSERT_FALSE(short_list);
  EXPECT_NE(short_list.error().message.find("lists 2 values"), std::string::npos);
  const auto negative = element_modulus_weights({1.0, -2.0, 3.0}, 1000.0, 3, "FEM");
  ASSERT_FALSE(negative);
  EXPECT_NE(negative.error().message.find("tetrahedron 1"), std::string::npos);
  EXPECT_FALSE(element_modulus_weights({1.0, std::numeric_limits<double>::infinity(), 3.0}, 1000.0, 3, "FEM"));
}

}  // namespace
}  // namespace hof::mechanics
