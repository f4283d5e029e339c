// Hexahedral FEM (SOFA's HexahedronFEMForceField) against analytic solutions: element
// stiffness properties, patch tests, rigid-motion invariance, the Timoshenko cantilever, a
// sparse-grid liver run with its fine surface mapped trilinearly, and the errors.

#include "hof/mechanics/detail/hexahedron_fem_force_field.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "hof/mechanics/model_parameters.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/hex_grid.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

using testing::box_grid;
using testing::distort_interior;
using testing::hex_field;

ModelConfig static_config(const mesh::HexGrid& grid, FemMethod method, double young = 1000.0, double poisson = 0.3) {
  ModelConfig c;
  c.name = "block";
  c.positions = grid.nodes;
  c.hexahedra = grid.hexes;
  c.mass.kind = MassKind::kUniform;
  c.gravity_m_per_s2 = Vec3::Zero();
  c.force_fields.push_back(hex_field(method, young, poisson));
  c.ode.kind = OdeSolverKind::kStatic;
  c.ode.newton_iterations = 20;
  c.ode.newton_residual_tolerance_n = 1e-11;
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  return c;
}

std::vector<std::int32_t> nodes_where(const std::vector<Vec3>& nodes, const std::function<bool(const Vec3&)>& pred) {
  std::vector<std::int32_t> out;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (pred(nodes[i])) out.push_back(static_cast<std::int32_t>(i));
  }
  return out;
}

// Internal (elastic) forces of the model at positions x.
Eigen::VectorXd internal_forces(const MechanicalModel& model, const std::vector<Vec3>& x) {
  MechanicalState state = make_state(model);
  for (std::size_t n = 0; n < x.size(); ++n) state.x.segment<3>(3 * static_cast<Eigen::Index>(n)) = x[n];
  Eigen::VectorXd f = Eigen::VectorXd::Zero(state.x.size());
  compute_forces(model, state, state.x, state.v, f);
  return f;
}

std::string method_name(const ::testing::TestParamInfo<FemMethod>& info) {
  switch (info.param) {
    case FemMethod::kSmall:
      return "Small";
    case FemMethod::kLarge:
      return "Large";
    case FemMethod::kPolar:
      return "Polar";
  }
  return "Unknown";
}

// ---- the element --------------------------------------------------------------------------

TEST(HexElement, StiffnessIsSymmetricWithExactlySixRigidModes) {
  std::array<Vec3, 8> corners{};
  for (int c = 0; c < 8; ++c) {
    const auto& s = mesh::kHexCornerSigns[c];
    corners[c] = Vec3(0.02 * (s[0] + 1), 0.015 * (s[1] + 1), 0.01 * (s[2] + 1));
  }
  corners[6] += Vec3(0.004, -0.002, 0.003);  // not a box
  const Lame lame = lame_parameters(5000.0, 0.45);
  double min_det = 0.0;
  const auto k = hex_element_stiffness(corners, lame.lambda, lame.mu, min_det);
  EXPECT_GT(min_det, 0.0);
  EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
  const Eigen::SelfAdjointEigenSolver<HexahedronFemForceField::ElementMatrix> eigen(k);
  const auto values = eigen.eigenvalues();  // ascending
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(values[i]), 1e-10 * values[23]) << i;
  EXPECT_GT(values[6], 1e-4 * values[23]);
}

TEST(HexElement, UnitCubeStiffnessMatchesTheClosedForm) {
  // The unit cube at ν = 0: the element represents a uniform stretch ε exactly, so its
  // energy ½ uᵀ K u is the continuum's ½ E ε² V, and det J = V/8 at every Gauss point.
  std::array<Vec3, 8> corners{};
  for (int c = 0; c < 8; ++c) {
    const auto& s = mesh::kHexCornerSigns[c];
    corners[c] = Vec3((s[0] + 1) / 2.0, (s[1] + 1) / 2.0, (s[2] + 1) / 2.0);
  }
  const Lame lame = lame_parameters(1.0, 0.0);
  double min_det = 0.0;
  const auto k = hex_element_stiffness(corners, lame.lambda, lame.mu, min_det);
  EXPECT_NEAR(min_det, 0.125, 1e-15);  // det J = V/8
  Eigen::Matrix<double, 24, 1> u = Eigen::Matrix<double, 24, 1>::Zero();
  const double strain = 0.01;
  for (int c = 0; c < 8; ++c) u[3 * c] = strain * corners[c].x();
  EXPECT_NEAR(0.5 * u.dot(k * u), 0.5 * strain * strain, 1e-16);
}

// The assembled stiffness is −∂f/∂x: at a rigidly rotated rest state (no stress, so the
// rotation's own derivative does not contribute) the co-rotational tangent R K Rᵀ is exact,
// and matches central differences of the forces.
class HexTangentTest : public ::testing::TestWithParam<FemMethod> {};

TEST_P(HexTangentTest, AssembledStiffnessMatchesFiniteDifferencesAfterARotation) {
  mesh::HexGrid grid = box_grid({3, 3, 2}, Vec3(0.04, 0.03, 0.02));
  distort_interior(grid, 0.2);
  HexahedronFemConfig config;
  config.method = GetParam();
  config.element_young_modulus_pa.assign(grid.hexes.size(), 0.0);
  config.element_young_modulus_pa[2] = 20000.0;
  auto field = HexahedronFemForceField::make(grid.nodes, grid.hexes, config, "FEM");
  ASSERT_TRUE(field) << field.error().to_string();
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  (*field)->collect_couplings(pairs);
  BlockSparseMatrix k = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(grid.nodes.size()), pairs);
  (*field)->bind(k);
  ForceFieldState state = (*field)->make_state();
  const Mat3 r = Eigen::AngleAxisd(0.8, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(grid.nodes.size()));
  for (std::size_t n = 0; n < grid.nodes.size(); ++n)
    x.segment<3>(3 * static_cast<Eigen::Index>(n)) = r * grid.nodes[n];
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  (*field)->add_force(x, v, state, f);
  k.set_zero();
  (*field)->add_stiffness(state, 1.0, k);
  const Eigen::MatrixXd dense = k.to_dense();
  const double step = 1e-7;
  Eigen::MatrixXd numeric(x.size(), x.size());
  for (Eigen::Index d = 0; d < x.size(); ++d) {
    Eigen::VectorXd plus = x, minus = x;
    plus[d] += step;
    minus[d] -= step;
    Eigen::VectorXd f_plus = Eigen::VectorXd::Zero(x.size()), f_minus = Eigen::VectorXd::Zero(x.size());
    ForceFieldState scratch = (*field)->make_state();
    (*field)->add_force(plus, v, scratch, f_plus);
    (*field)->add_force(minus, v, scratch, f_minus);
    numeric.col(d) = -(f_plus - f_minus) / (2.0 * step);
  }
  EXPECT_LT((dense - numeric).norm(), 1e-6 * dense.norm());
  EXPECT_LT((dense - dense.transpose()).norm(), 1e-12 * dense.norm());

  // Setting the whole matrix (upper half summed, the rest completed) gives the same, in double
  // and in the single-precision copy, whatever the matrix held before.
  std::fill_n(k.values(), BlockSparseMatrix::kBlockStride * k.block_count(), 7.0);
  ASSERT_TRUE((*field)->set_stiffness(state, 1.0, k));
  EXPECT_LT((k.to_dense() - dense).norm(), 1e-12 * dense.norm());
  k.prepare_single_precision();
  ASSERT_TRUE((*field)->set_stiffness_single(state, 1.0, k));
  const Eigen::VectorXd probe = Eigen::VectorXd::LinSpaced(x.size(), -1.0, 2.0);
  std::vector<float, Eigen::aligned_allocator<float>> probe_single(4 * grid.nodes.size() + 4, 0.0f);
  BlockSparseMatrix::round_to_single(probe.data(), probe_single.data(), 0, grid.nodes.size());
  Eigen::VectorXd product(x.size());
  k.multiply_single(probe_single.data(), product);
  EXPECT_LT((product - dense * probe).norm(), 1e-6 * (dense * probe).norm());
}

INSTANTIATE_TEST_SUITE_P(Methods, HexTangentTest,
                         ::testing::Values(FemMethod::kSmall, FemMethod::kLarge, FemMethod::kPolar), method_name);

// ---- patch tests ----------------------------------------------------------------------------

// The stress resultant of nodal forces: for any linear field, −Σ_c f_c X_cᵀ = σ V (the
// divergence theorem with Σ_c X_c ∇N_cᵀ = I), so uniform stress σ gives exactly σ V.
Mat3 stress_resultant(const Eigen::VectorXd& f, const std::vector<Vec3>& rest) {
  Mat3 sum = Mat3::Zero();
  for (std::size_t n = 0; n < rest.size(); ++n)
    sum -= f.segment<3>(3 * static_cast<Eigen::Index>(n)) * rest[n].transpose();
  return sum;
}

class HexPatchTest : public ::testing::TestWithParam<FemMethod> {};

TEST_P(HexPatchTest, ASingleGeneralHexUnderUniformStrainCarriesHookesStress) {
  const double young = 3000.0, poisson = 0.3;
  mesh::HexGrid one = box_grid({2, 2, 2}, Vec3(0.02, 0.03, 0.025));
  one.nodes[6] += Vec3(0.004, 0.003, -0.002);
  one.nodes[1] += Vec3(0.002, -0.001, 0.001);
  auto model = build_model(static_config(one, GetParam(), young, poisson));
  ASSERT_TRUE(model) << model.error().to_string();
  // A symmetric displacement gradient (no rotation): exact for `small`; `large` and `polar`
  // take their rotation from the element's edges (SOFA's rules), which a stretch of a
  // general, non-cubic hexahedron turns slightly: second order in the strain.
  Mat3 a;
  a << 2e-3, 5e-4, -3e-4, 5e-4, -1e-3, 4e-4, -3e-4, 4e-4, 1.5e-3;
  std::vector<Vec3> x;
  for (const Vec3& p : one.nodes) x.push_back(p + a * p + Vec3(0.1, -0.2, 0.3));
  const Mat3 resultant = stress_resultant(internal_forces(*model, x), one.nodes);
  const Lame l = lame_parameters(young, poisson);
  const Mat3 sigma = l.lambda * a.trace() * Mat3::Identity() + 2.0 * l.mu * a;
  const double volume = mesh::hex_volume(one.nodes, one.hexes[0]);
  const double tolerance = GetParam() == FemMethod::kSmall ? 1e-9 : 2e-3;
  EXPECT_LT((resultant / volume - sigma).norm(), tolerance * sigma.norm()) << resultant / volume << "\n\n" << sigma;
}

TEST_P(HexPatchTest, AGridUnderUniaxialStrainHasTheAnalyticFaceResultants) {
  // ε = diag(ε, 0, 0): σ_xx = (λ + 2μ) ε on the x faces, σ_yy = σ_zz = λ ε on the others.
  const double young = 3000.0, poisson = 0.3, strain = 0.01;
  const Vec3 size(0.3, 0.2, 0.1);
  const mesh::HexGrid grid = box_grid({4, 3, 3}, size);
  auto model = build_model(static_config(grid, GetParam(), young, poisson));
  ASSERT_TRUE(model);
  std::vector<Vec3> x;
  for (const Vec3& p : grid.nodes) x.emplace_back((1.0 + strain) * p.x(), p.y(), p.z());
  const Eigen::VectorXd f = internal_forces(*model, x);
  const Lame l = lame_parameters(young, poisson);
  Vec3 x_face = Vec3::Zero(), y_face = Vec3::Zero();
  for (std::int32_t n : nodes_where(grid.nodes, [&](const Vec3& p) { return p.x() == size.x(); }))
    x_face += f.segment<3>(3 * n);
  for (std::int32_t n : nodes_where(grid.nodes, [&](const Vec3& p) { return p.y() == size.y(); }))
    y_face += f.segment<3>(3 * n);
  // The internal force on a face is minus the traction that holds it.
  EXPECT_NEAR(-x_face.x(), (l.lambda + 2.0 * l.mu) * strain * size.y() * size.z(), 1e-9);
  EXPECT_NEAR(-y_face.y(), l.lambda * strain * size.x() * size.z(), 1e-9);
  // Interior nodes are in equilibrium.
  for (std::int32_t n : nodes_where(grid.nodes, [&](const Vec3& p) {
         return p.x() > 0 && p.x() < size.x() && p.y() > 0 && p.y() < size.y() && p.z() > 0 && p.z() < size.z();
       })) {
    EXPECT_LT(f.segment<3>(3 * n).norm(), 1e-12) << "node " << n;
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, HexPatchTest,
                         ::testing::Values(FemMethod::kSmall, FemMethod::kLarge, FemMethod::kPolar), method_name);

// SOFA's `polar` (HexahedronFEMForceField::computeRotationPolar) rotates by the polar factor
// of the matrix of the element's averaged edges, relative to that at rest — not by the polar
// factor of the deformation gradient. The two differ on a cell longer on one axis: a shear
// along its long axis turns the edge matrix less than F.
TEST(HexPolar, RotatesByThePolarFactorOfTheAveragedEdgesAsSofa) {
  const Vec3 size(2.0, 1.0, 1.0);
  const mesh::HexGrid cell = box_grid({2, 2, 2}, size);
  auto field = HexahedronFemForceField::make(cell.nodes, cell.hexes,
                                             *hex_field(FemMethod::kPolar, 1000.0, 0.3).hexahedron_fem, "FEM");
  ASSERT_TRUE(field) << field.error().to_string();
  Mat3 gradient;  // a shear of the long axis plus some stretch
  gradient << 1.05, 0.0, 0.0, 0.35, 0.98, 0.0, 0.0, 0.1, 1.0;
  Eigen::VectorXd x(24);
  for (std::size_t c = 0; c < 8; ++c) x.segment<3>(3 * static_cast<Eigen::Index>(c)) = gradient * cell.nodes[c];
  ForceFieldState state = (*field)->make_state();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
  (*field)->add_force(x, Eigen::VectorXd::Zero(24), state, f);

  // f = −R K (Rᵀx − X) with R the polar factor of the edges now (G diag(size)) times that
  // at rest (diag(size): the identity), by an SVD.
  const auto polar_factor = [](const Mat3& m) {
    const Eigen::JacobiSVD<Mat3> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return Mat3(svd.matrixU() * svd.matrixV().transpose());
  };
  const mesh::Hex& corners = cell.hexes[0];  // the stiffness is in corner order
  const auto expected_force = [&](const Mat3& r) {
    Eigen::VectorXd u(24);
    for (int c = 0; c < 8; ++c) {
      const auto node = static_cast<std::size_t>(corners[static_cast<std::size_t>(c)]);
      u.segment<3>(3 * c) = r.transpose() * x.segment<3>(3 * static_cast<Eigen::Index>(node)) - cell.nodes[node];
    }
    const Eigen::VectorXd local = -((*field)->element_stiffness(0) * u);
    Eigen::VectorXd out(24);
    for (int c = 0; c < 8; ++c)
      out.segment<3>(3 * static_cast<Eigen::Index>(corners[static_cast<std::size_t>(c)])) = r * local.segment<3>(3 * c);
    return out;
  };
  const Eigen::VectorXd sofa = expected_force(polar_factor(gradient * size.asDiagonal()));
  EXPECT_LT((f - sofa).norm(), 1e-9 * sofa.norm()) << f.transpose() << "\n" << sofa.transpose();
  // The rule matters here: the polar factor of F itself gives another force.
  const Eigen::VectorXd of_f = expected_force(polar_factor(gradient));
  EXPECT_GT((of_f - sofa).norm(), 1e-2 * sofa.norm());
}

TEST(HexPatchTest, DistortedGridReproducesAnAffineFieldExactly) {
  // Boundary nodes on an affine field, interior nodes free: trilinear elements with full
  // integration pass the patch test on general hexahedra (Hughes 1987, §3.9), so the static
  // solution is the affine field at every node.
  mesh::HexGrid grid = box_grid({4, 4, 4}, Vec3(1.0, 1.0, 1.0));
  distort_interior(grid, 0.25);
  ModelConfig c = static_config(grid, FemMethod::kSmall);
  FixedConstraintConfig fixed;
  fixed.indices = nodes_where(grid.nodes, [](const Vec3& p) {
    return p.x() == 0.0 || p.y() == 0.0 || p.z() == 0.0 || p.x() == 1.0 || p.y() == 1.0 || p.z() == 1.0;
  });
  c.fixed.push_back(fixed);
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  Mat3 a;
  a << 0.010, -0.004, 0.002, 0.003, -0.006, 0.005, -0.001, 0.007, 0.008;
  auto affine = [&](const Vec3& p) -> Vec3 { return p + a * p + Vec3(0.01, -0.02, 0.03); };
  for (std::int32_t n : fixed.indices) state.x.segment<3>(3 * n) = affine(grid.nodes[static_cast<std::size_t>(n)]);
  ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
  for (std::size_t n = 0; n < grid.nodes.size(); ++n) {
    EXPECT_LT((state.position(static_cast<std::int32_t>(n)) - affine(grid.nodes[n])).norm(), 1e-12) << "node " << n;
  }
  EXPECT_LT(max_residual_force(*model, state), 1e-10);
}

// ---- rigid motions --------------------------------------------------------------------------

double rigid_motion_force(FemMethod method, double angle, const Vec3& axis) {
  mesh::HexGrid grid = box_grid({4, 3, 3}, Vec3(0.1, 0.08, 0.06));
  distort_interior(grid, 0.2);
  auto model = build_model(static_config(grid, method, 5000.0, 0.45));
  EXPECT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  const Mat3 r = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  for (std::size_t n = 0; n < grid.nodes.size(); ++n) {
    state.x.segment<3>(3 * static_cast<Eigen::Index>(n)) = r * grid.nodes[n] + Vec3(1.0, 2.0, -3.0);
  }
  // Relative to the force of a unit strain on one cell face, E h².
  return max_residual_force(*model, state) / (5000.0 * 0.02 * 0.02);
}

class HexRigidMotionTest : public ::testing::TestWithParam<FemMethod> {};

TEST_P(HexRigidMotionTest, CorotationalGivesNoForceForAnyRotation) {
  for (const auto& [angle, axis] : std::vector<std::pair<double, Vec3>>{{std::numbers::pi / 2, Vec3(0.3, -0.5, 0.8)},
                                                                        {std::numbers::pi / 6, Vec3(1, 2, 3)},
                                                                        {std::numbers::pi, Vec3(1, 1, 0)}}) {
    EXPECT_LT(rigid_motion_force(GetParam(), angle, axis), 1e-9) << "rotation by " << angle << " rad";
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, HexRigidMotionTest, ::testing::Values(FemMethod::kLarge, FemMethod::kPolar),
                         method_name);

TEST(HexRigidMotion, LinearFemIsNotRotationInvariant) {
  EXPECT_LT(rigid_motion_force(FemMethod::kSmall, 0.0, Vec3::UnitZ()), 1e-9);  // translation alone
  EXPECT_GT(rigid_motion_force(FemMethod::kSmall, std::numbers::pi / 6, Vec3(1, 2, 3)), 1e-2);
}

// ---- cantilever -----------------------------------------------------------------------------

// Cantilever L/h = 10 clamped at x = 0, shear load P on the free end, m cells through the
// thickness. Trilinear elements with full integration are too stiff in bending (parasitic
// shear); the error falls as the grid is refined.
double cantilever_tip_ratio(int m, FemMethod method, double load = 1.0) {
  const double length = 1.0, h = 0.1, young = 1e6, poisson = 0.3;
  const mesh::HexGrid grid = box_grid({10 * m + 1, m + 1, m + 1}, Vec3(length, h, h));
  ModelConfig c = static_config(grid, method, young, poisson);
  FixedConstraintConfig clamp;
  clamp.name = "clamp";
  clamp.indices = nodes_where(grid.nodes, [](const Vec3& p) { return p.x() == 0.0; });
  c.fixed.push_back(clamp);
  // Consistent loads of a uniform shear traction P/h² on the end face: each node gets the area
  // it shares with its neighbours (a quarter of each face quad it touches).
  ForceFieldConfig tip;
  tip.name = "tip";
  tip.constant_force = ConstantForceConfig{};
  const double cell = h / m;
  for (std::int32_t n : nodes_where(grid.nodes, [&](const Vec3& p) { return p.x() == length; })) {
    const Vec3& p = grid.nodes[static_cast<std::size_t>(n)];
    const double wy = (p.y() == 0.0 || p.y() == h) ? 0.5 : 1.0;
    const double wz = (p.z() == 0.0 || p.z() == h) ? 0.5 : 1.0;
    tip.constant_force->indices.push_back(n);
    tip.constant_force->forces.push_back(Vec3(0, -load * wy * wz * cell * cell / (h * h), 0));
  }
  c.force_fields.push_back(tip);
  c.ode.newton_iterations = method == FemMethod::kSmall ? 1 : 10;
  auto model = build_model(c);
  EXPECT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  EXPECT_TRUE(step(*model, state)) << state.divergence.reason;
  const auto end_nodes = nodes_where(grid.nodes, [&](const Vec3& p) { return p.x() == length; });
  double deflection = 0.0;
  for (std::int32_t n : end_nodes) deflection -= state.position(n).y() - grid.nodes[static_cast<std::size_t>(n)].y();
  deflection /= static_cast<double>(end_nodes.size());
  // Timoshenko beam: δ = P L³/(3EI) + P L/(κ G A), κ = 5/6 for a rectangular section
  // (Timoshenko & Gere, "Mechanics of Materials", 1972, §9.11).
  const double inertia = h * h * h * h / 12.0;
  const double shear_modulus = young / (2.0 * (1.0 + poisson));
  const double timoshenko =
      load * length * length * length / (3.0 * young * inertia) + load * length / (5.0 / 6.0 * shear_modulus * h * h);
  return deflection / timoshenko;
}

TEST(HexCantilever, TipDeflectionConvergesToTimoshenko) {
  const double r1 = cantilever_tip_ratio(1, FemMethod::kSmall);
  const double r2 = cantilever_tip_ratio(2, FemMethod::kSmall);
  const double r4 = cantilever_tip_ratio(4, FemMethod::kSmall);
  const double r6 = cantilever_tip_ratio(6, FemMethod::kSmall);
  std::printf("tip deflection / Timoshenko: %.4f (1 cell through), %.4f (2), %.4f (4), %.4f (6)\n", r1, r2, r4, r6);
  EXPECT_LT(r1, r2);
  EXPECT_LT(r2, r4);
  EXPECT_LT(r4, r6);
  EXPECT_NEAR(r6, 1.0, 0.05);
  // Co-rotational elements agree under a small load (tip deflection L/25,000). At L/28 (the
  // load above) they do not: the linear solution stretches each rotated element by ~θ²/2,
  // an axial force far above the tip load, that the co-rotational equilibrium removes.
  EXPECT_NEAR(cantilever_tip_ratio(2, FemMethod::kLarge, 1e-3), r2, 1e-3 * r2);
  EXPECT_NEAR(cantilever_tip_ratio(2, FemMethod::kPolar, 1e-3), r2, 1e-3 * r2);
}

// ---- per-element material, mass, errors --------------------------------------------------------

// A bar of two materials in series under uniaxial stress σ stretches by σ (L₁/E₁ + L₂/E₂);
// with ν = 0 trilinear elements represent it exactly.
TEST(HexMaterialRegions, TwoMaterialsInSeriesStretchAsSprings) {
  const double soft = 3000.0, stiff = 12000.0, stress = 30.0;
  const Vec3 size(0.3, 0.1, 0.1);
  const mesh::HexGrid grid = box_grid({4, 2, 2}, size);
  ModelConfig c = static_config(grid, FemMethod::kSmall, soft, 0.0);
  std::vector<double> per_element(grid.hexes.size(), 0.0);
  for (std::size_t e = 0; e < grid.hexes.size(); ++e) {
    if (grid.nodes[static_cast<std::size_t>(grid.hexes[e][0])].x() > 0.15) per_element[e] = stiff;
  }
  c.force_fields[0].hexahedron_fem->element_young_modulus_pa = per_element;
  for (int axis = 0; axis < 3; ++axis) {
    FixedConstraintConfig roller;
    roller.directions = {axis == 0, axis == 1, axis == 2};
    roller.indices = nodes_where(grid.nodes, [&](const Vec3& p) { return p[axis] == 0.0; });
    c.fixed.push_back(roller);
  }
  ForceFieldConfig load;
  load.name = "traction";
  load.constant_force = ConstantForceConfig{};
  for (std::int32_t n : nodes_where(grid.nodes, [&](const Vec3& p) { return p.x() == size.x(); })) {
    const Vec3& p = grid.nodes[static_cast<std::size_t>(n)];
    const double wy = (p.y() == 0.0 || p.y() == size.y()) ? 0.5 : 1.0;
    const double wz = (p.z() == 0.0 || p.z() == size.z()) ? 0.5 : 1.0;
    load.constant_force->indices.push_back(n);
    load.constant_force->forces.push_back(Vec3(stress * wy * wz * size.y() * size.z(), 0, 0));  // one cell across
  }
  c.force_fields.push_back(load);
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  MechanicalState state = make_state(*model);
  ASSERT_TRUE(step(*model, state));
  const double expected = stress * (0.2 / soft + 0.1 / stiff);  // cells of 0.1 m, the last one stiff
  for (std::int32_t n : nodes_where(grid.nodes, [&](const Vec3& p) { return p.x() == size.x(); })) {
    EXPECT_NEAR(state.position(n).x() - size.x(), expected, 1e-9 * expected);
  }
}

TEST(HexMaterialRegions, PerElementPoissonRatioChangesOnlyItsElements) {
  const mesh::HexGrid grid = box_grid({4, 2, 2}, Vec3(0.3, 0.1, 0.1));
  HexahedronFemConfig config;
  config.element_poisson_ratio.assign(grid.hexes.size(), 0.0);
  config.element_poisson_ratio[1] = 0.1;
  auto field = HexahedronFemForceField::make(grid.nodes, grid.hexes, config, "FEM");
  ASSERT_TRUE(field) << field.error().to_string();
  EXPECT_EQ((*field)->distinct_stiffness_count(), 2u);  // all cells are the same box
  EXPECT_TRUE((*field)->element_stiffness(0).isApprox((*field)->element_stiffness(2)));
  EXPECT_FALSE((*field)->element_stiffness(0).isApprox((*field)->element_stiffness(1), 1e-3));
}

TEST(HexErrors, WrongLengthListsAndBadValuesNameTheComponent) {
  const mesh::HexGrid grid = box_grid({3, 2, 2}, Vec3(0.2, 0.1, 0.1));
  ModelConfig c = static_config(grid, FemMethod::kLarge);
  c.force_fields[0].hexahedron_fem->element_young_modulus_pa.assign(grid.hexes.size() + 1, 1000.0);
  auto long_list = build_model(c);
  ASSERT_FALSE(long_list);
  EXPECT_NE(long_list.error().message.find("HexahedronFEMForceField 'FEM': youngModulus has 3 values but the topology "
                                           "has 2 hexahedra"),
            std::string::npos)
      << long_list.error().message;
  c.force_fields[0].hexahedron_fem->element_young_modulus_pa.clear();
  c.force_fields[0].hexahedron_fem->element_poisson_ratio = {0.0, 0.5};
  auto bad_ratio = build_model(c);
  ASSERT_FALSE(bad_ratio);
  EXPECT_NE(bad_ratio.error().message.find("poissonRatio of hexahedron 1 is 0.5"), std::string::npos)
      << bad_ratio.error().message;
  c.force_fields[0].hexahedron_fem->element_poisson_ratio.clear();
  c.force_fields[0].hexahedron_fem->poisson_ratio = 0.5;
  auto incompressible = build_model(c);
  ASSERT_FALSE(incompressible);
  EXPECT_NE(incompressible.error().message.find("HexahedronFEMForceField 'FEM': poissonRatio must be in (-1, 0.5)"),
            std::string::npos);
  c.force_fields[0].hexahedron_fem->poisson_ratio = 0.3;
  c.force_fields[0].hexahedron_fem->young_modulus_pa = 0.0;
  EXPECT_FALSE(build_model(c));
  c.force_fields[0].hexahedron_fem->young_modulus_pa = 1000.0;
  c.hexahedra[1][3] = 99;
  auto missing = build_model(c);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("hexahedron 1 refers to node 99"), std::string::npos)
      << missing.error().message;
}

TEST(HexErrors, AnInvertedOrFlatHexahedronIsNamed) {
  mesh::HexGrid grid = box_grid({3, 3, 2}, Vec3(0.2, 0.2, 0.1));
  ModelConfig c = static_config(grid, FemMethod::kLarge);
  // Element 3 with its bottom and top faces swapped: inside out.
  std::swap_ranges(c.hexahedra[3].begin(), c.hexahedra[3].begin() + 4, c.hexahedra[3].begin() + 4);
  auto inverted = build_model(c);
  ASSERT_FALSE(inverted);
  EXPECT_NE(inverted.error().message.find("HexahedronFEMForceField 'FEM': hexahedron 3 (nodes"), std::string::npos)
      << inverted.error().message;
  EXPECT_NE(inverted.error().message.find("inverted"), std::string::npos);
  // A cell squashed flat (its top corners moved onto the bottom face).
  c.hexahedra = grid.hexes;
  for (int corner = 4; corner < 8; ++corner) {
    c.positions[static_cast<std::size_t>(c.hexahedra[0][corner])].z() = 0.0;
  }
  auto flat = build_model(c);
  ASSERT_FALSE(flat);
  EXPECT_NE(flat.error().message.find("hexahedron 0 (nodes"), std::string::npos) << flat.error().message;
}

TEST(HexMass, DiagonalMassLumpsAnEighthOfEachCellWithItsOwnDensity) {
  const mesh::HexGrid grid = box_grid({3, 2, 2}, Vec3(0.2, 0.1, 0.1));
  ModelConfig c = static_config(grid, FemMethod::kLarge);
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  auto uniform = build_model(c);
  ASSERT_TRUE(uniform) << uniform.error().to_string();
  EXPECT_NEAR(uniform->total_mass_kg(), 1000.0 * 0.002, 1e-12);
  EXPECT_NEAR(uniform->node_mass_kg[0], 1000.0 * 0.001 / 8.0, 1e-15);  // a corner: one cell
  c.mass.element_mass_density_kg_per_m3 = {0.0, 3000.0};
  auto regions = build_model(c);
  ASSERT_TRUE(regions) << regions.error().to_string();
  EXPECT_NEAR(regions->total_mass_kg(), 1000.0 * 0.001 + 3000.0 * 0.001, 1e-12);
  c.mass.element_mass_density_kg_per_m3 = {1.0};
  auto wrong = build_model(c);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("2 hexahedra"), std::string::npos) << wrong.error().message;
}

// SOFA's sparse grid gives a cell the surface crosses half the stiffness (fillWeighted):
// HexahedronFEMForceField multiplies the element matrix by SparseGridTopology's stiffness
// coefficient. Its mass coefficient is read by HexahedronFEMForceFieldAndMass only:
// DiagonalMass (DiagonalMass::computeVertexMass) lumps each cell's whole volume.
// A SOFA scene (fill_scales_mass false): SOFA's DiagonalMass lumps the whole cell while the
// stiffness is halved. HoF's own bodies weigh what they fill (checked after).
TEST(HexMass, AHalfFilledCellIsHalfAsStiffButDiagonalMassLumpsItWhole) {
  const mesh::HexGrid grid = box_grid({3, 2, 2}, Vec3(0.2, 0.1, 0.1));
  ModelConfig c = static_config(grid, FemMethod::kLarge);
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.element_fill = {0.5, 1.0};
  const ModelConfig hof_body = c;
  c.fill_scales_mass = false;
  auto own_model = build_model(hof_body);
  ASSERT_TRUE(own_model) << own_model.error().to_string();
  EXPECT_NEAR(own_model->total_mass_kg(), 1000.0 * 0.0015, 1e-12);
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  EXPECT_NEAR(model->total_mass_kg(), 1000.0 * 0.002, 1e-12);
  const mesh::Hex& half = grid.hexes[0];
  const mesh::Hex& full = grid.hexes[1];
  const auto corner_of_only = [&](const mesh::Hex& own, const mesh::Hex& other) {
    for (mesh::NodeIndex n : own) {
      if (std::find(other.begin(), other.end(), n) == other.end()) return static_cast<std::size_t>(n);
    }
    return std::size_t{0};
  };
  EXPECT_NEAR(model->node_mass_kg[corner_of_only(half, full)], 1000.0 * 0.001 / 8.0, 1e-15);
  EXPECT_NEAR(model->node_mass_kg[corner_of_only(full, half)], 1000.0 * 0.001 / 8.0, 1e-15);
  const auto* fem = dynamic_cast<const HexahedronFemForceField*>(model->force_fields.front().get());
  ASSERT_NE(fem, nullptr);
  EXPECT_LT((fem->element_stiffness(0) - 0.5 * fem->element_stiffness(1)).norm(),
            1e-12 * fem->element_stiffness(1).norm());
}

TEST(HexMass, TetrahedralDiagonalMassHonoursPerElementDensity) {
  const testing::BoxMesh box = testing::box_mesh(1, 1, 1, Vec3(0.1, 0.1, 0.1));
  ModelConfig c;
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.mass.element_mass_density_kg_per_m3.assign(box.tets.size(), 0.0);
  c.mass.element_mass_density_kg_per_m3[0] = 7000.0;  // the six tets have equal volumes
  auto model = build_model(c);
  ASSERT_TRUE(model) << model.error().to_string();
  EXPECT_NEAR(model->total_mass_kg(), 1e-3 * (5.0 * 1000.0 + 7000.0) / 6.0, 1e-12);
}

TEST(HexParameters, YoungModulusAndPoissonRatioAreAddressable) {
  ModelConfig c = static_config(box_grid({2, 2, 2}, Vec3(0.1, 0.1, 0.1)), FemMethod::kLarge);
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kForceField, 0}, ParameterId::kYoungModulus}, 2500.0));
  EXPECT_EQ(c.force_fields[0].hexahedron_fem->young_modulus_pa, 2500.0);
  ASSERT_TRUE(set_parameter(c, ParameterRef{{ComponentKind::kForceField, 0}, ParameterId::kPoissonRatio}, 0.2));
  EXPECT_EQ(*get_parameter(c, ParameterRef{{ComponentKind::kForceField, 0}, ParameterId::kPoissonRatio}), 0.2);
  EXPECT_FALSE(set_parameter(c, ParameterRef{{ComponentKind::kForceField, 0}, ParameterId::kPoissonRatio}, 0.5));
  EXPECT_EQ(component_name(c, {ComponentKind::kForceField, 0}), "FEM");
  const auto refs = parameter_refs(c);
  EXPECT_NE(
      std::find(refs.begin(), refs.end(), ParameterRef{{ComponentKind::kForceField, 0}, ParameterId::kYoungModulus}),
      refs.end());
}

}  // namespace
}  // namespace hof::mechanics
