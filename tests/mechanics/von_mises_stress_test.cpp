// Von Mises display stress (von_mises_stress.h): the principal-stretch formula against hand
// values, and the per-element and per-node stress of a body against the analytic value of a
// uniform stretch.

#include "hof/mechanics/von_mises_stress.h"

#include <gtest/gtest.h>

#include <cmath>

#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_mesh;
using testing::BoxMesh;

ModelConfig fem_config(const BoxMesh& box, double young, double poisson) {
  ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  return c;
}

// σᵢ = λ tr ε + 2μ εᵢ with εᵢ = sᵢ − 1. Uniaxial ε along x: σ = (λ+2μ, λ, λ) ε, von Mises 2με.
// Pure shear ε = (e, −e, 0): σ = 2μ (e, −e, 0), differences 4μe, 2μe, 2μe, von Mises
// √(½(16 + 4 + 4)) μe = 2√3 μe. Equal stretches (a pressure) have none.
TEST(VonMisesFromStretches, UniaxialShearAndHydrostaticHandValues) {
  const double lambda = 1700.0, mu = 1150.0, e = 0.02;
  EXPECT_NEAR(von_mises_from_stretches(Vec3(1.0 + e, 1.0, 1.0), lambda, mu), 2.0 * mu * e, 1e-9);
  EXPECT_NEAR(von_mises_from_stretches(Vec3(1.0 - e, 1.0, 1.0), lambda, mu), 2.0 * mu * e, 1e-9)
      << "compression: the same size";
  EXPECT_NEAR(von_mises_from_stretches(Vec3(1.0 + e, 1.0 - e, 1.0), lambda, mu), 2.0 * std::sqrt(3.0) * mu * e, 1e-9);
  EXPECT_NEAR(von_mises_from_stretches(Vec3(1.1, 1.1, 1.1), lambda, mu), 0.0, 1e-9);
  EXPECT_NEAR(von_mises_from_stretches(Vec3(1.0, 1.0, 1.0), lambda, mu), 0.0, 0.0);
  // The order of the principal stretches does not matter.
  EXPECT_NEAR(von_mises_from_stretches(Vec3(1.03, 0.99, 1.01), lambda, mu),
              von_mises_from_stretches(Vec3(0.99, 1.01, 1.03), lambda, mu), 1e-9);
}

// Display stress: under a uniform stretch ε along x (others held), σ = diag(λ+2μ, λ, λ) ε, whose
// von Mises value is 2με; a rigid rotation has none; a region with 4E has 4 times the stress.
TEST(VonMisesStress, MatchesTheAnalyticValueOfAUniformStretchAndIgnoresRotation) {
  const BoxMesh box = box_mesh(3, 2, 2, Vec3(0.3, 0.2, 0.2));
  ModelConfig c = fem_config(box, 3000.0, 0.3);
  std::vector<double> per_element(box.tets.size(), 0.0);
  per_element[5] = 12000.0;
  c.force_fields[0].tetrahedron_fem->element_young_modulus_pa = per_element;
  const VonMisesStress stress(c);
  ASSERT_TRUE(stress.available());
  EXPECT_EQ(stress.source(), "FEM");
  const double strain = 0.01;
  std::vector<double> x;
  for (const Vec3& p : box.nodes) {
    x.push_back((1.0 + strain) * p.x());
    x.push_back(p.y());
    x.push_back(p.z());
  }
  std::vector<double> element;
  stress.element_stress(x, element);
  const Lame lame = lame_parameters(3000.0, 0.3);
  ASSERT_EQ(element.size(), box.tets.size());
  for (std::size_t t = 0; t < element.size(); ++t) {
    EXPECT_NEAR(element[t], (t == 5 ? 4.0 : 1.0) * 2.0 * lame.mu * strain, 1e-9) << "element " << t;
  }
  // Per node: the volume-weighted mean, so a node away from element 5 reads exactly 2με.
  std::vector<double> node;
  stress.node_stress(x, node);
  EXPECT_NEAR(node[static_cast<std::size_t>(box.index(3, 2, 2))], 2.0 * lame.mu * strain, 1e-9);

  const Mat3 rotation = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  x.clear();
  for (const Vec3& p : box.nodes) {
    const Vec3 q = rotation * p + Vec3(0.1, -0.2, 0.3);
    x.insert(x.end(), {q.x(), q.y(), q.z()});
  }
  stress.element_stress(x, element);
  for (const double s : element) EXPECT_NEAR(s, 0.0, 1e-9);
}

TEST(VonMisesStress, IsUnavailableForASpringModel) {
  const BoxMesh box = box_mesh(1, 1, 1, Vec3(0.1, 0.1, 0.1));
  ModelConfig c = fem_config(box, 1000.0, 0.3);
  c.force_fields[0] = ForceFieldConfig{};
  c.force_fields[0].name = "springs";
  c.force_fields[0].mesh_springs = MeshSpringConfig{};
  EXPECT_FALSE(VonMisesStress(c).available());
}

}  // namespace
}  // namespace hof::mechanics
