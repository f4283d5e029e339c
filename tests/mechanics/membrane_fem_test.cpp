// Membrane FEM (SOFA's TriangleFEMForceField / TriangularFEMForceField) against the analytic
// plane-stress and plane-strain solutions, rigid-motion invariance, the stiffness against
// finite differences, and its errors. Also the per-element Poisson ratio of the tetrahedral
// fields (tissue regions), which build_model splits into one field per ratio.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "hof/mechanics/step.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

struct Sheet {
  std::vector<Vec3> nodes;
  std::vector<mesh::Tri> triangles;
  int nx, ny;
  [[nodiscard]] std::int32_t index(int i, int j) const { return j * (nx + 1) + i; }
};

// The rectangle [0, length] × [0, height] in z = 0, nx × ny cells of two triangles each, the
// diagonals alternating so the mesh has no preferred direction.
Sheet sheet(int nx, int ny, double length, double height) {
  Sheet s{{}, {}, nx, ny};
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i)
      s.nodes.emplace_back(i == nx ? length : length * i / nx, j == ny ? height : height * j / ny, 0.0);
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const std::int32_t a = s.index(i, j), b = s.index(i + 1, j), c = s.index(i + 1, j + 1), d = s.index(i, j + 1);
      if ((i + j) % 2 == 0) {
        s.triangles.push_back({a, b, c});
        s.triangles.push_back({a, c, d});
      } else {
        s.triangles.push_back({a, b, d});
        s.triangles.push_back({b, c, d});
      }
    }
  }
  return s;
}

ModelConfig membrane_config(const Sheet& s, const TriangleFemConfig& fem) {
  ModelConfig c;
  c.name = "sheet";
  c.positions = s.nodes;
  c.triangles = s.triangles;
  c.mass.kind = MassKind::kUniform;
  c.gravity_m_per_s2 = Vec3::Zero();
  ForceFieldConfig f;
  f.name = "membrane";
  f.triangle_fem = fem;
  c.force_fields.push_back(f);
  c.ode.kind = OdeSolverKind::kStatic;
  c.ode.newton_iterations = 20;
  c.ode.newton_residual_tolerance_n = 1e-12;
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  return c;
}

struct Stretch {
  double strain_x;
  double strain_y;
};

// A sheet pulled at x = L by a uniform traction σ (consistent nodal loads: each edge segment
// gives half its force to each end), held by rollers at x = 0 and y = 0, z held everywhere
// (a membrane has no stiffness out of its plane). Returns the mean strains.
Stretch pull(const TriangleFemConfig& fem, double stress_pa) {
  const double length = 0.1, height = 0.05;
  const Sheet s = sheet(8, 4, length, height);
  ModelConfig c = membrane_config(s, fem);
  ConstantForceConfig load;
  for (int j = 0; j <= s.ny; ++j) {
    const double share = (j == 0 || j == s.ny) ? 0.5 : 1.0;
    load.indices.push_back(s.index(s.nx, j));
    load.forces.emplace_back(share * stress_pa * fem.thickness_m * height / s.ny, 0.0, 0.0);
  }
  ForceFieldConfig pullf;
  pullf.name = "pull";
  pullf.constant_force = load;
  c.force_fields.push_back(pullf);
  FixedConstraintConfig x_roller{"xroller", {}, std::nullopt, false, {true, false, false}};
  FixedConstraintConfig y_roller{"yroller", {}, std::nullopt, false, {false, true, false}};
  FixedConstraintConfig flat{"flat", {}, std::nullopt, true, {false, false, true}};
  for (int j = 0; j <= s.ny; ++j) x_roller.indices.push_back(s.index(0, j));
  for (int i = 0; i <= s.nx; ++i) y_roller.indices.push_back(s.index(i, 0));
  c.fixed = {x_roller, y_roller, flat};
  auto model = build_model(c);
  EXPECT_TRUE(model.has_value()) << (model ? "" : model.error().message);
  if (!model) return {};
  MechanicalState state = make_state(*model);
  EXPECT_TRUE(step(*model, state));
  EXPECT_LT(max_residual_force(*model, state), 1e-9);
  double ux = 0.0, uy = 0.0;
  for (int j = 0; j <= s.ny; ++j) ux += state.x[3 * s.index(s.nx, j)] - length;
  for (int i = 0; i <= s.nx; ++i) uy += state.x[3 * s.index(i, s.ny) + 1] - height;
  return {ux / (s.ny + 1) / length, uy / (s.nx + 1) / height};
}

TEST(MembraneFem, UniaxialPlaneStressMatchesAnalytic) {
  // Plane stress, uniaxial σ: ε_x = σ/E, ε_y = −ν σ/E (Timoshenko & Goodier, "Theory of
  // Elasticity", §2 Hooke's law with σ_y = σ_z = 0).
  for (FemMethod method : {FemMethod::kSmall, FemMethod::kLarge}) {
    TriangleFemConfig fem;
    fem.young_modulus_pa = 3000.0;
    fem.poisson_ratio = 0.35;
    fem.thickness_m = 0.002;
    fem.method = method;
    const double stress = 0.3;  // Pa: strain 1e-4, small enough for the linear law
    const Stretch got = pull(fem, stress);
    const double expected = stress / fem.young_modulus_pa;
    EXPECT_NEAR(got.strain_x, expected, 0.01 * expected) << static_cast<int>(method);
    EXPECT_NEAR(got.strain_y, -fem.poisson_ratio * expected, 0.01 * fem.poisson_ratio * expected);
  }
}

TEST(MembraneFem, PlaneStrainIsStifferByOneMinusNuSquared) {
  // Plane strain (ε_z = 0), σ_y = 0: ε_x = σ (1 − ν²)/E, ε_y = −ν(1 + ν) σ/E.
  TriangleFemConfig fem;
  fem.young_modulus_pa = 3000.0;
  fem.poisson_ratio = 0.35;
  fem.thickness_m = 0.002;
  fem.plane_strain = true;
  const Stretch got = pull(fem, 0.3);
  const double e = 0.3 / fem.young_modulus_pa, nu = fem.poisson_ratio;
  EXPECT_NEAR(got.strain_x, e * (1.0 - nu * nu), 0.01 * e);
  EXPECT_NEAR(got.strain_y, -nu * (1.0 + nu) * e, 0.01 * nu * e);
}

// A curved patch (a piece of a cylinder), so that rotations about every axis matter.
Sheet curved_patch() {
  Sheet s = sheet(5, 4, 0.05, 0.04);
  for (Vec3& p : s.nodes) p.z() = 0.02 * std::sin(20.0 * p.x()) + 0.01 * p.y();
  return s;
}

Eigen::VectorXd forces_at(const ModelConfig& c, const std::vector<Vec3>& positions) {
  auto model = build_model(c);
  EXPECT_TRUE(model.has_value());
  MechanicalState state = make_state(*model);
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(positions.size()));
  for (std::size_t i = 0; i < positions.size(); ++i) x.segment<3>(3 * static_cast<Eigen::Index>(i)) = positions[i];
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  compute_forces(*model, state, x, state.v, f);
  return f;
}

TEST(MembraneFem, RigidMotionsGiveNoForceWhenCoRotational) {
  const Sheet s = curved_patch();
  TriangleFemConfig fem;
  fem.young_modulus_pa = 5000.0;
  fem.thickness_m = 0.001;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(1.1, Vec3(0.3, -0.8, 0.5).normalized()).toRotationMatrix();
  std::vector<Vec3> moved;
  for (const Vec3& p : s.nodes) moved.push_back(r * p + Vec3(0.2, -0.1, 0.05));
  // The force a 1% stretch gives, as the scale of "no force".
  std::vector<Vec3> stretched;
  for (const Vec3& p : s.nodes) stretched.push_back(Vec3(1.01 * p.x(), p.y(), p.z()));
  const double scale = forces_at(membrane_config(s, fem), stretched).norm();
  ASSERT_GT(scale, 0.0);
  EXPECT_LT(forces_at(membrane_config(s, fem), moved).norm(), 1e-9 * scale);
  fem.method = FemMethod::kSmall;  // linear: a rotation strains it (the test can fail)
  EXPECT_GT(forces_at(membrane_config(s, fem), moved).norm(), 10.0 * scale);
}

TEST(MembraneFem, StiffnessIsTheForceDerivativeAtRest) {
  const Sheet s = curved_patch();
  TriangleFemConfig fem;
  fem.young_modulus_pa = 5000.0;
  fem.thickness_m = 0.001;
  ModelConfig c = membrane_config(s, fem);
  auto model = build_model(c);
  ASSERT_TRUE(model.has_value());
  MechanicalState state = make_state(*model);
  Eigen::VectorXd f0 = Eigen::VectorXd::Zero(state.x.size());
  compute_forces(*model, state, state.x, state.v, f0);
  BlockSparseMatrix k = model->pattern;
  k.set_zero();
  model->force_fields[0]->add_stiffness(state.field_states[0], 1.0, k);
  const Eigen::MatrixXd dense = k.to_dense();
  const double h = 1e-7;
  for (Eigen::Index d : {0, 7, 20, 41}) {
    Eigen::VectorXd x = state.x;
    x[d] += h;
    Eigen::VectorXd f1 = Eigen::VectorXd::Zero(x.size());
    compute_forces(*model, state, x, state.v, f1);
    const Eigen::VectorXd column = -(f1 - f0) / h;
    EXPECT_LT((column - dense.col(d)).norm(), 1e-4 * dense.col(d).norm() + 1e-9) << "dof " << d;
  }
}

TEST(MembraneFem, MassOnTrianglesIsDensityTimesArea) {
  const Sheet s = sheet(4, 2, 0.1, 0.05);
  TriangleFemConfig fem;
  ModelConfig c = membrane_config(s, fem);
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 2.0;  // per area on a triangle topology, as SOFA
  auto model = build_model(c);
  ASSERT_TRUE(model.has_value()) << model.error().message;
  EXPECT_NEAR(model->total_mass_kg(), 2.0 * 0.1 * 0.05, 1e-12);
}

TEST(MembraneFem, BadInputsAreNamed) {
  Sheet s = sheet(2, 1, 0.1, 0.05);
  TriangleFemConfig fem;
  fem.poisson_ratio = 0.5;
  auto model = build_model(membrane_config(s, fem));
  ASSERT_FALSE(model.has_value());
  EXPECT_NE(model.error().message.find("TriangleFEMForceField 'membrane'"), std::string::npos);
  EXPECT_NE(model.error().message.find("poissonRatio"), std::string::npos);
  fem = {};
  fem.element_young_modulus_pa = {1.0, 2.0};
  model = build_model(membrane_config(s, fem));
  ASSERT_FALSE(model.has_value());
  EXPECT_NE(model.error().message.find("youngModulus lists 2 values"), std::string::npos) << model.error().message;
  fem = {};
  s.nodes[s.index(1, 1)] = s.nodes[s.index(0, 0)] + 0.5 * (s.nodes[s.index(2, 1)] - s.nodes[s.index(0, 0)]);
  s.nodes[s.index(1, 0)] = s.nodes[s.index(0, 0)] + 0.25 * (s.nodes[s.index(2, 1)] - s.nodes[s.index(0, 0)]);
  model = build_model(membrane_config(s, fem));
  ASSERT_FALSE(model.has_value());
  EXPECT_NE(model.error().message.find("degenerate"), std::string::npos) << model.error().message;
}

// ---- per-element Poisson ratio of the tetrahedral fields --------------------------------------

ModelConfig block_config(const testing::BoxMesh& box) {
  ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = MassKind::kUniform;
  c.gravity_m_per_s2 = Vec3::Zero();
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{};
  fem.tetrahedron_fem->young_modulus_pa = 1000.0;
  fem.tetrahedron_fem->poisson_ratio = 0.3;
  c.force_fields.push_back(fem);
  return c;
}

TEST(ElementPoissonRatio, SplitFieldsSumToTheWhole) {
  const testing::BoxMesh box = testing::box_mesh(3, 2, 2, Vec3(0.03, 0.02, 0.02));
  std::vector<Vec3> deformed;
  for (const Vec3& p : box.nodes) deformed.push_back(p + Vec3(0.1 * p.y() * p.x() * 10, -0.05 * p.z(), 0.02 * p.x()));
  // Half the elements at ν = 0.45 (and twice as stiff), half at the field's 0.3.
  ModelConfig mixed = block_config(box);
  auto& fem = *mixed.force_fields[0].tetrahedron_fem;
  fem.element_poisson_ratio.assign(box.tets.size(), 0.0);
  fem.element_young_modulus_pa.assign(box.tets.size(), 0.0);
  ModelConfig soft = block_config(box), hard = block_config(box);
  soft.tets.clear();
  hard.tets.clear();
  for (std::size_t t = 0; t < box.tets.size(); ++t) {
    if (t % 2 == 0) {
      fem.element_poisson_ratio[t] = 0.45;
      fem.element_young_modulus_pa[t] = 2000.0;
      hard.tets.push_back(box.tets[t]);
    } else {
      soft.tets.push_back(box.tets[t]);
    }
  }
  hard.force_fields[0].tetrahedron_fem->poisson_ratio = 0.45;
  hard.force_fields[0].tetrahedron_fem->young_modulus_pa = 2000.0;
  auto model = build_model(mixed);
  ASSERT_TRUE(model.has_value()) << model.error().message;
  EXPECT_EQ(model->force_fields.size(), 2u);
  const Eigen::VectorXd whole = forces_at(mixed, deformed);
  const Eigen::VectorXd parts = forces_at(soft, deformed) + forces_at(hard, deformed);
  ASSERT_GT(whole.norm(), 0.0);
  EXPECT_LT((whole - parts).norm(), 1e-9 * whole.norm());
  // ... and differs from the uniform material (the ratio is applied).
  EXPECT_GT((whole - forces_at(block_config(box), deformed)).norm(), 0.1 * whole.norm());
}

TEST(ElementPoissonRatio, WrongLengthIsNamed) {
  const testing::BoxMesh box = testing::box_mesh(1, 1, 1, Vec3(0.01, 0.01, 0.01));
  ModelConfig c = block_config(box);
  c.force_fields[0].tetrahedron_fem->element_poisson_ratio = {0.3, 0.3};
  auto model = build_model(c);
  ASSERT_FALSE(model.has_value());
  EXPECT_NE(model.error().message.find("TetrahedronFEMForceField 'FEM'"), std::string::npos);
  EXPECT_NE(model.error().message.find("2 values for 6"), std::string::npos) << model.error().message;
}

}  // namespace
}  // namespace hof::mechanics

namespace hof::mechanics {
namespace {

TEST(MembraneFem, APreTensionedSheetIsStiffAcrossItsPlaneInTheTangent) {
  // A flat drum skin (rest shape 95% of the drawn one, border held) pushed across its plane:
  // the tension's restoring force is in the tangent the implicit solver uses (the
  // initial-stress term) — without it the matrix would be zero across the plane.
  const Sheet s = sheet(6, 6, 0.06, 0.06);
  TriangleFemConfig fem;
  fem.young_modulus_pa = 5000.0;
  fem.thickness_m = 0.001;
  fem.rest_scale = 0.95;
  ModelConfig c = membrane_config(s, fem);
  auto model = build_model(c);
  ASSERT_TRUE(model.has_value()) << model.error().message;
  MechanicalState state = make_state(*model);
  const Eigen::Index centre = 3 * s.index(3, 3) + 2;  // z of the middle node
  const double h = 1e-6;
  Eigen::VectorXd x = state.x;
  x[centre] += h;
  Eigen::VectorXd f0 = Eigen::VectorXd::Zero(x.size()), f1 = Eigen::VectorXd::Zero(x.size());
  compute_forces(*model, state, state.x, state.v, f0);
  compute_forces(*model, state, x, state.v, f1);
  const double restoring = -(f1[centre] - f0[centre]) / h;
  ASSERT_GT(restoring, 0.0);  // the tension pulls it back
  BlockSparseMatrix k = model->pattern;
  k.set_zero();
  compute_forces(*model, state, state.x, state.v, f0);  // the tangent at the flat state
  model->force_fields[0]->add_stiffness(state.field_states[0], 1.0, k);
  EXPECT_NEAR(k.to_dense()(centre, centre), restoring, 0.05 * restoring);
}

}  // namespace
}  // namespace hof::mechanics
