#include "hof/mechanics/detail/neo_hookean_force_field.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace hof::mechanics {
namespace {

using Field = NeoHookeanForceField;

// A general (not right-angled) tetrahedron, positively oriented.
std::vector<Vec3> single_tet_rest() {
  return {Vec3(0.0, 0.0, 0.0), Vec3(1.0, 0.1, 0.0), Vec3(0.2, 0.9, 0.1), Vec3(0.1, 0.2, 1.1)};
}
const std::vector<mesh::Tet> kSingleTet = {{0, 1, 2, 3}};

// Unit cube split into six tetrahedra around the diagonal 0-7 (node index bits: x=1, y=2,
// z=4). Half of them are negatively oriented, which the field must reorder.
std::vector<Vec3> cube_rest() {
  std::vector<Vec3> nodes;
  for (int n = 0; n < 8; ++n) nodes.emplace_back(n & 1, (n >> 1) & 1, (n >> 2) & 1);
  return nodes;
}
const std::vector<mesh::Tet> kCubeTets = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                          {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

std::unique_ptr<Field> make_field(const std::vector<Vec3>& rest, const std::vector<mesh::Tet>& tets,
                                  double young = 1.0e4, double poisson = 0.45) {
  auto field = Field::make(rest, tets, NeoHookeanConfig{young, poisson, {}, {}}, "tissue");
  EXPECT_TRUE(field.has_value()) << field.error().message;
  return field.has_value() ? std::move(*field) : nullptr;
}

Eigen::VectorXd flatten(const std::vector<Vec3>& points) {
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) x.segment<3>(3 * static_cast<Eigen::Index>(i)) = points[i];
  return x;
}

// Positions x_i = F X_i + t.
Eigen::VectorXd affine(const std::vector<Vec3>& rest, const Mat3& f, const Vec3& t) {
  std::vector<Vec3> moved;
  for (const Vec3& p : rest) moved.push_back(f * p + t);
  return flatten(moved);
}

Eigen::VectorXd forces(const Field& field, const Eigen::VectorXd& x, ForceFieldState& state) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  field.add_force(x, Eigen::VectorXd::Zero(x.size()), state, f);
  return f;
}
Eigen::VectorXd forces(const Field& field, const Eigen::VectorXd& x) {
  ForceFieldState state = field.make_state();
  return forces(field, x, state);
}

// Dense K = −∂f/∂x at x, assembled through collect_couplings / bind / add_stiffness.
Eigen::MatrixXd stiffness(Field& field, const Eigen::VectorXd& x) {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  field.collect_couplings(pairs);
  BlockSparseMatrix k = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(x.size() / 3), pairs);
  field.bind(k);
  k.set_zero();
  ForceFieldState state = field.make_state();
  forces(field, x, state);
  field.add_stiffness(state, 1.0, k);
  return k.to_dense();
}

// −∂f/∂x by central differences of the forces.
Eigen::MatrixXd stiffness_by_differences(const Field& field, const Eigen::VectorXd& x, double h) {
  Eigen::MatrixXd k(x.size(), x.size());
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    k.col(j) = -(forces(field, plus) - forces(field, minus)) / (2.0 * h);
  }
  return k;
}

// ∂E/∂x by central differences of the potential energy.
Eigen::VectorXd energy_gradient_by_differences(const Field& field, const Eigen::VectorXd& x, double h) {
  const ForceFieldState state = field.make_state();
  Eigen::VectorXd g(x.size());
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    g(j) = (field.potential_energy(plus, state) - field.potential_energy(minus, state)) / (2.0 * h);
  }
  return g;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  q.normalize();
  return q.toRotationMatrix();
}

double signed_volume(const Eigen::VectorXd& x) {
  const Vec3 x0 = x.segment<3>(0);
  return (x.segment<3>(3) - x0).dot((x.segment<3>(6) - x0).cross(x.segment<3>(9) - x0)) / 6.0;
}

bool all_finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

double lame_mu(double young, double poisson) { return lame_parameters(young, poisson).mu; }

// Checks K = Kᵀ and that its eigenvalues are ≥ −1e-9 · max |eigenvalue|; returns the spectrum.
Eigen::VectorXd expect_symmetric_psd(const Eigen::MatrixXd& k) {
  EXPECT_TRUE(all_finite(k));
  const double scale = k.cwiseAbs().maxCoeff();
  EXPECT_LE((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (k + k.transpose()));
  const Eigen::VectorXd values = eigen.eigenvalues();
  const double largest = values.cwiseAbs().maxCoeff();
  EXPECT_GT(largest, 0.0);
  EXPECT_GE(values.minCoeff(), -1e-9 * largest) << "eigenvalues: " << values.transpose();
  return values;
}

// ---- rest state and rigid motions ------------------------------------------------------

TEST(NeoHookean, RestStateHasZeroForceAndEnergy) {
  for (const auto& [rest, tets] : {std::pair{single_tet_rest(), kSingleTet}, std::pair{cube_rest(), kCubeTets}}) {
    const auto field = make_field(rest, tets);
    const Eigen::VectorXd x = flatten(rest);
    EXPECT_LE(forces(*field, x).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_NEAR(field->potential_energy(x, field->make_state()), 0.0, 1e-9);
  }
  const auto field = make_field(single_tet_rest(), kSingleTet);
  EXPECT_EQ(field->energy_density(Mat3::Identity()), 0.0);
  EXPECT_LE(field->first_piola_stress(Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(NeoHookean, RigidRotationsGiveZeroForce) {
  const auto field = make_field(cube_rest(), kCubeTets);
  std::mt19937 rng(7);
  std::vector<Mat3> rotations;
  for (int r = 0; r < 8; ++r) rotations.push_back(random_rotation(rng));
  // Half turns: the SVD of diag(−1, −1, 1) etc. must come back as proper rotations.
  rotations.push_back(Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitZ()).toRotationMatrix());
  rotations.push_back(Eigen::AngleAxisd(std::numbers::pi, Vec3(1.0, 2.0, -0.5).normalized()).toRotationMatrix());
  for (const Mat3& r : rotations) {
    const Eigen::VectorXd x = affine(cube_rest(), r, Vec3(0.3, -2.0, 5.0));
    // Force scale: E · area ≈ 1e4 N for this cube.
    EXPECT_LE(forces(*field, x).cwiseAbs().maxCoeff(), 1e-8) << r;
    EXPECT_NEAR(field->potential_energy(x, field->make_state()), 0.0, 1e-9);
    EXPECT_LE(field->first_piola_stress(r).cwiseAbs().maxCoeff(), 1e-9);
  }
}

// ---- material law ----------------------------------------------------------------------

TEST(NeoHookean, SimpleShearCauchyStress) {
  const double young = 1.0e4, poisson = 0.45;
  const double mu = lame_mu(young, poisson);
  const auto field = make_field(single_tet_rest(), kSingleTet, young, poisson);
  for (double gamma : {0.01, 0.1, 0.5, 1.0}) {
    Mat3 f = Mat3::Identity();
    f(0, 1) = gamma;
    const Mat3 cauchy = field->first_piola_stress(f) * f.transpose() / f.determinant();
    EXPECT_NEAR(cauchy(0, 1), mu * gamma, 1e-9 * mu * gamma) << "gamma " << gamma;
    EXPECT_NEAR(cauchy(1, 0), mu * gamma, 1e-9 * mu * gamma) << "gamma " << gamma;
    EXPECT_NEAR(cauchy(0, 0), mu * gamma * gamma, 1e-9 * mu * gamma * gamma) << "gamma " << gamma;
    EXPECT_NEAR(cauchy(1, 1), 0.0, 1e-9 * mu * gamma * gamma) << "gamma " << gamma;
    EXPECT_NEAR(cauchy(2, 2), 0.0, 1e-9 * mu * gamma * gamma) << "gamma " << gamma;
    EXPECT_NEAR(cauchy(0, 2), 0.0, 1e-9 * mu * gamma * gamma);
    EXPECT_NEAR(cauchy(1, 2), 0.0, 1e-9 * mu * gamma * gamma);
    // W = μ/2 γ² under isochoric simple shear.
    EXPECT_NEAR(field->energy_density(f), 0.5 * mu * gamma * gamma, 1e-9 * mu * gamma * gamma);
  }
}

TEST(NeoHookean, NearlyIncompressibleUniaxialStretchMatchesClosedForm) {
  const double young = 3.0e3, poisson = 0.4999;
  const double mu = lame_mu(young, poisson);
  const auto field = make_field(single_tet_rest(), kSingleTet, young, poisson);
  auto stress = [&](double stretch, double lateral) {
    return field->first_piola_stress(Vec3(stretch, lateral, lateral).asDiagonal());
  };
  for (double stretch : {0.7, 0.9, 1.1, 1.5, 2.0}) {
    // Free lateral faces: bisection on the lateral stretch s for P22(s) = 0.
    double lo = 0.2, hi = 3.0;
    ASSERT_LT(stress(stretch, lo)(1, 1), 0.0);
    ASSERT_GT(stress(stretch, hi)(1, 1), 0.0);
    for (int iteration = 0; iteration < 200; ++iteration) {
      const double mid = 0.5 * (lo + hi);
      (stress(stretch, mid)(1, 1) < 0.0 ? lo : hi) = mid;
    }
    const double lateral = 0.5 * (lo + hi);
    const Mat3 p = stress(stretch, lateral);
    const double expected = mu * (stretch - 1.0 / (stretch * stretch));
    EXPECT_NEAR(p(0, 0), expected, 0.02 * std::abs(expected)) << "stretch " << stretch;
    EXPECT_NEAR(p(2, 2), 0.0, 1e-6 * mu);
    EXPECT_NEAR(stretch * lateral * lateral, 1.0, 1e-3) << "volume should be nearly preserved";
  }
}

// ---- consistency: forces, energy and stiffness -----------------------------------------

TEST(NeoHookean, ForcesAreMinusEnergyGradient) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto field = make_field(single_tet_rest(), kSingleTet);
  const Eigen::VectorXd rest = flatten(single_tet_rest());
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd x = rest;
    for (Eigen::Index i = 0; i < x.size(); ++i) x(i) += 0.2 * unit(rng);
    ASSERT_GT(signed_volume(x), 0.3 * signed_volume(rest));
    const Eigen::VectorXd f = forces(*field, x);
    const Eigen::VectorXd g = energy_gradient_by_differences(*field, x, 1e-6);
    EXPECT_LE((f + g).cwiseAbs().maxCoeff(), 1e-6 * f.cwiseAbs().maxCoeff()) << "trial " << trial;
  }
  // The same on several elements sharing nodes (checks the coloured scatter).
  const auto cube = make_field(cube_rest(), kCubeTets);
  Eigen::VectorXd x = flatten(cube_rest());
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) += 0.1 * unit(rng);
  const Eigen::VectorXd f = forces(*cube, x);
  const Eigen::VectorXd g = energy_gradient_by_differences(*cube, x, 1e-6);
  EXPECT_LE((f + g).cwiseAbs().maxCoeff(), 1e-6 * f.cwiseAbs().maxCoeff());
}

TEST(NeoHookean, ForcesAreMinusEnergyGradientOnInvertedElement) {
  // The clamped extension below the singular-value threshold is an energy too: an inverted
  // element's forces are its exact gradient (away from the measure-zero kinks).
  const auto field = make_field(single_tet_rest(), kSingleTet);
  std::vector<Vec3> points = single_tet_rest();
  points[3] = Vec3(0.3, 0.25, -0.4);  // node 3 pushed through the opposite face
  const Eigen::VectorXd x = flatten(points);
  ASSERT_LT(signed_volume(x), 0.0);
  const Eigen::VectorXd f = forces(*field, x);
  const Eigen::VectorXd g = energy_gradient_by_differences(*field, x, 1e-6);
  EXPECT_LE((f + g).cwiseAbs().maxCoeff(), 1e-6 * f.cwiseAbs().maxCoeff());
}

TEST(NeoHookean, StiffnessMatchesForceDifferences) {
  // Stretched states with J > 1: every mode of the tangent is positive there (checked by hand
  // from the closed forms), so the PSD projection is inactive and K is the exact Hessian.
  std::mt19937 rng(3);
  const std::vector<Vec3> singular_values = {Vec3(1.2, 1.1, 1.05), Vec3(1.3, 1.0, 0.95), Vec3(1.15, 1.15, 1.02)};
  for (const Vec3& s : singular_values) {
    auto field = make_field(single_tet_rest(), kSingleTet, 1.0e4, 0.3);
    const Mat3 f = random_rotation(rng) * s.asDiagonal() * random_rotation(rng).transpose();
    const Eigen::VectorXd x = affine(single_tet_rest(), f, Vec3(0.1, 0.2, 0.3));
    const Eigen::MatrixXd k = stiffness(*field, x);
    const Eigen::MatrixXd k_fd = stiffness_by_differences(*field, x, 1e-6);
    const double scale = k.cwiseAbs().maxCoeff();
    EXPECT_LE((k - k_fd).cwiseAbs().maxCoeff(), 1e-6 * scale) << "singular values " << s.transpose();
    // Rigid translations are in the null space.
    Eigen::VectorXd translation = Eigen::VectorXd::Zero(12);
    for (int n = 0; n < 4; ++n) translation.segment<3>(3 * n) = Vec3(1.0, -2.0, 0.5);
    EXPECT_LE((k * translation).cwiseAbs().maxCoeff(), 1e-9 * scale);
  }
}

TEST(NeoHookean, StiffnessAtRestMatchesForceDifferencesOnMesh) {
  // At rest the only zero modes of the tangent are the rotations: compare on the cube mesh.
  auto field = make_field(cube_rest(), kCubeTets);
  const Eigen::VectorXd x = flatten(cube_rest());
  const Eigen::MatrixXd k = stiffness(*field, x);
  const Eigen::MatrixXd k_fd = stiffness_by_differences(*field, x, 1e-6);
  EXPECT_LE((k - k_fd).cwiseAbs().maxCoeff(), 1e-6 * k.cwiseAbs().maxCoeff());
  const Eigen::VectorXd values = expect_symmetric_psd(k);
  // Six rigid modes, the rest strictly positive.
  EXPECT_GT(values(6), 1e-6 * values.maxCoeff());
}

TEST(NeoHookean, StiffnessIsSymmetricPsdUnderCompressionAndInversion) {
  std::mt19937 rng(5);
  // Compressed to J = 0.3 (rotated, anisotropic): the exact Hessian is indefinite there, the
  // projected stiffness must not be.
  {
    auto field = make_field(single_tet_rest(), kSingleTet);
    const Mat3 f = random_rotation(rng) * Vec3(1.0, 0.6, 0.5).asDiagonal() * random_rotation(rng).transpose();
    const Eigen::VectorXd x = affine(single_tet_rest(), f, Vec3::Zero());
    expect_symmetric_psd(stiffness(*field, x));
    const Eigen::MatrixXd exact = stiffness_by_differences(*field, x, 1e-6);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (exact + exact.transpose()));
    EXPECT_LT(eigen.eigenvalues().minCoeff(), -1e-3 * eigen.eigenvalues().maxCoeff())
        << "the test state should need the projection";
  }
  // Uniformly compressed to J = 0.3.
  {
    auto field = make_field(single_tet_rest(), kSingleTet);
    const Eigen::VectorXd x = affine(single_tet_rest(), std::cbrt(0.3) * Mat3::Identity(), Vec3::Zero());
    expect_symmetric_psd(stiffness(*field, x));
  }
  // Inverted: one node pushed through the opposite face, and a mirrored element.
  {
    auto field = make_field(single_tet_rest(), kSingleTet);
    std::vector<Vec3> points = single_tet_rest();
    points[3] = Vec3(0.3, 0.25, -0.4);
    expect_symmetric_psd(stiffness(*field, flatten(points)));
    const Mat3 mirror = Vec3(-1.0, 1.0, 1.0).asDiagonal();
    expect_symmetric_psd(stiffness(*field, affine(single_tet_rest(), mirror, Vec3::Zero())));
  }
  // Squeezed to a point and flattened to a plane.
  {
    auto field = make_field(single_tet_rest(), kSingleTet);
    expect_symmetric_psd(stiffness(*field, affine(single_tet_rest(), Mat3::Zero(), Vec3(0.3, 0.3, 0.3))));
    expect_symmetric_psd(stiffness(*field, affine(single_tet_rest(), Vec3(1.0, 1.0, 0.0).asDiagonal(), Vec3::Zero())));
  }
}

// ---- inversion and degenerate states ---------------------------------------------------

TEST(NeoHookean, InvertedElementIsPushedBack) {
  const auto field = make_field(single_tet_rest(), kSingleTet);
  std::vector<std::vector<Vec3>> states;
  for (const Vec3& through : {Vec3(0.3, 0.25, -0.4), Vec3(0.2, 0.2, -0.05), Vec3(0.4, 0.3, -2.0)}) {
    std::vector<Vec3> points = single_tet_rest();
    points[3] = through;
    states.push_back(points);
  }
  std::vector<Vec3> mirrored;
  for (const Vec3& p : single_tet_rest()) mirrored.push_back(Vec3(-p.x(), p.y(), p.z()));
  states.push_back(mirrored);
  for (const auto& points : states) {
    const Eigen::VectorXd x = flatten(points);
    ASSERT_LT(signed_volume(x), 0.0);
    const Eigen::VectorXd f = forces(*field, x);
    ASSERT_TRUE(f.allFinite());
    ASSERT_GT(f.norm(), 0.0);
    EXPECT_TRUE(std::isfinite(field->potential_energy(x, field->make_state())));
    // A small step along the forces (largest node move 1e-3 m) increases the signed volume.
    const Eigen::VectorXd moved = x + (1e-3 / f.cwiseAbs().maxCoeff()) * f;
    EXPECT_GT(signed_volume(moved), signed_volume(x));
    // And the energy decreases along the force.
    EXPECT_LT(field->potential_energy(moved, field->make_state()), field->potential_energy(x, field->make_state()));
  }
}

TEST(NeoHookean, CollapsedElementsGiveFiniteRestoringForces) {
  const auto field = make_field(single_tet_rest(), kSingleTet);
  // F = 0: all nodes at one point. Flattened: all nodes in the plane z = 0.
  std::vector<Vec3> flat;
  for (const Vec3& p : single_tet_rest()) flat.push_back(Vec3(p.x(), p.y(), 0.0));
  for (const Eigen::VectorXd& x : {affine(single_tet_rest(), Mat3::Zero(), Vec3(0.3, 0.3, 0.3)), flatten(flat)}) {
    const Eigen::VectorXd f = forces(*field, x);
    ASSERT_TRUE(f.allFinite());
    ASSERT_GT(f.norm(), 0.0);
    EXPECT_TRUE(std::isfinite(field->potential_energy(x, field->make_state())));
    const Eigen::VectorXd moved = x + (1e-3 / f.cwiseAbs().maxCoeff()) * f;
    EXPECT_GT(signed_volume(moved), 0.0);
  }
  // The material functions are finite for any finite F, whatever its sign or rank.
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> unit(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    Mat3 f;
    for (int i = 0; i < 9; ++i) f(i) = unit(rng);
    if (trial % 3 == 0) f.col(2) = 0.5 * f.col(0) - f.col(1);  // rank 2
    if (trial % 5 == 0) f.row(1).setZero();
    EXPECT_TRUE(field->first_piola_stress(f).allFinite()) << f;
    EXPECT_TRUE(std::isfinite(field->energy_density(f))) << f;
  }
  EXPECT_TRUE(field->first_piola_stress(Mat3::Zero()).allFinite());
  EXPECT_TRUE(std::isfinite(field->energy_density(Mat3::Zero())));
}

TEST(NeoHookean, StressIsContinuousAcrossTheThresholdAndZeroVolume) {
  const auto field = make_field(single_tet_rest(), kSingleTet);
  for (double s3 : {0.1, 0.0}) {
    const Mat3 below = field->first_piola_stress(Vec3(1.1, 0.9, s3 - 1e-9).asDiagonal());
    const Mat3 above = field->first_piola_stress(Vec3(1.1, 0.9, s3 + 1e-9).asDiagonal());
    EXPECT_LE((below - above).norm(), 1e-5 * above.norm()) << "at sigma3 = " << s3;
    // The energy changes by no more than its slope P33 times the 2e-9 step: no jump.
    const double jump = field->energy_density(Vec3(1.1, 0.9, s3 - 1e-9).asDiagonal()) -
                        field->energy_density(Vec3(1.1, 0.9, s3 + 1e-9).asDiagonal());
    EXPECT_NEAR(jump, -2e-9 * above(2, 2), 1e-3 * 2e-9 * std::abs(above(2, 2))) << "at sigma3 = " << s3;
  }
}

// ---- assembly on a large mesh ----------------------------------------------------------

TEST(NeoHookean, ParallelAssemblyMatchesPerElementSums) {
  // A 20x20x20 grid of cubes (48000 tets): the coloured loops run in parallel here. The
  // forces and K·v must equal the sums of single-element fields.
  constexpr int kCells = 20;
  const double h = 0.01;
  auto id = [](int i, int j, int k) { return static_cast<std::int32_t>(i + (kCells + 1) * (j + (kCells + 1) * k)); };
  std::vector<Vec3> rest;
  for (int k = 0; k <= kCells; ++k) {
    for (int j = 0; j <= kCells; ++j) {
      for (int i = 0; i <= kCells; ++i) rest.emplace_back(h * i, h * j, h * k);
    }
  }
  std::vector<mesh::Tet> tets;
  for (int k = 0; k < kCells; ++k) {
    for (int j = 0; j < kCells; ++j) {
      for (int i = 0; i < kCells; ++i) {
        std::array<std::int32_t, 8> c;
        for (int n = 0; n < 8; ++n) c[n] = id(i + (n & 1), j + ((n >> 1) & 1), k + ((n >> 2) & 1));
        for (const mesh::Tet& t : kCubeTets) tets.push_back({c[t[0]], c[t[1]], c[t[2]], c[t[3]]});
      }
    }
  }
  auto field = make_field(rest, tets);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd x = flatten(rest);
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) += 0.2 * h * unit(rng);
  Eigen::VectorXd v(x.size());
  for (Eigen::Index i = 0; i < v.size(); ++i) v(i) = unit(rng);

  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  field->collect_couplings(pairs);
  BlockSparseMatrix k = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(rest.size()), pairs);
  field->bind(k);
  k.set_zero();
  ForceFieldState state = field->make_state();
  const Eigen::VectorXd f = forces(*field, x, state);
  field->add_stiffness(state, 2.0, k);
  Eigen::VectorXd kv(x.size());
  k.multiply(v, kv);

  Eigen::VectorXd f_ref = Eigen::VectorXd::Zero(x.size());
  Eigen::VectorXd kv_ref = Eigen::VectorXd::Zero(x.size());
  for (const mesh::Tet& t : tets) {
    std::vector<Vec3> local_rest;
    Eigen::VectorXd local_x(12), local_v(12);
    for (int n = 0; n < 4; ++n) {
      local_rest.push_back(rest[t[n]]);
      local_x.segment<3>(3 * n) = x.segment<3>(3 * static_cast<Eigen::Index>(t[n]));
      local_v.segment<3>(3 * n) = v.segment<3>(3 * static_cast<Eigen::Index>(t[n]));
    }
    auto single = make_field(local_rest, kSingleTet);
    const Eigen::VectorXd local_f = forces(*single, local_x);
    const Eigen::VectorXd local_kv = 2.0 * (stiffness(*single, local_x) * local_v);
    for (int n = 0; n < 4; ++n) {
      f_ref.segment<3>(3 * static_cast<Eigen::Index>(t[n])) += local_f.segment<3>(3 * n);
      kv_ref.segment<3>(3 * static_cast<Eigen::Index>(t[n])) += local_kv.segment<3>(3 * n);
    }
  }
  EXPECT_LE((f - f_ref).cwiseAbs().maxCoeff(), 1e-10 * f_ref.cwiseAbs().maxCoeff());
  EXPECT_LE((kv - kv_ref).cwiseAbs().maxCoeff(), 1e-10 * kv_ref.cwiseAbs().maxCoeff());
  // Deterministic: the same inputs give bit-identical forces.
  EXPECT_EQ(forces(*field, x), f);
}

// ---- construction ----------------------------------------------------------------------

TEST(NeoHookean, RestInvertedTetIsReordered) {
  const auto forward = make_field(single_tet_rest(), kSingleTet);
  const auto swapped = make_field(single_tet_rest(), {{0, 2, 1, 3}});
  EXPECT_LE(forces(*swapped, flatten(single_tet_rest())).cwiseAbs().maxCoeff(), 1e-9);
  const Mat3 f = Vec3(1.3, 0.9, 1.1).asDiagonal();
  const Eigen::VectorXd x = affine(single_tet_rest(), f, Vec3::Zero());
  EXPECT_LE((forces(*forward, x) - forces(*swapped, x)).cwiseAbs().maxCoeff(), 1e-9 * forces(*forward, x).norm());
}

TEST(NeoHookean, InvalidParametersAreErrorsNamingTheComponent) {
  const auto rest = single_tet_rest();
  for (double young : {0.0, -5.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const auto field = Field::make(rest, kSingleTet, NeoHookeanConfig{young, 0.3, {}, {}}, "liver");
    ASSERT_FALSE(field.has_value());
    EXPECT_EQ(field.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(field.error().message.find("NeoHookeanForceField 'liver': youngModulus"), std::string::npos)
        << field.error().message;
  }
  for (double poisson : {0.5, 0.6, -1.0, -2.0, std::numeric_limits<double>::quiet_NaN()}) {
    const auto field = Field::make(rest, kSingleTet, NeoHookeanConfig{1.0e4, poisson, {}, {}}, "liver");
    ASSERT_FALSE(field.has_value());
    EXPECT_EQ(field.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(field.error().message.find("NeoHookeanForceField 'liver': poissonRatio must be in (-1, 0.5), got"),
              std::string::npos)
        << field.error().message;
  }
  const auto half = Field::make(rest, kSingleTet, NeoHookeanConfig{1.0e4, 0.5, {}, {}}, "liver");
  ASSERT_FALSE(half.has_value());
  EXPECT_EQ(half.error().message, "NeoHookeanForceField 'liver': poissonRatio must be in (-1, 0.5), got 0.5");
}

TEST(NeoHookean, BadMeshesAreErrorsNamingTheTetrahedron) {
  std::vector<Vec3> rest = single_tet_rest();
  rest.push_back(Vec3(2.0, 0.2, 0.0));  // nodes 4, 5 are collinear with nodes 0, 1
  rest.push_back(Vec3(3.0, 0.3, 0.0));
  const auto degenerate = Field::make(rest, {{0, 1, 2, 3}, {0, 1, 4, 5}}, NeoHookeanConfig{}, "liver");
  ASSERT_FALSE(degenerate.has_value());
  EXPECT_EQ(degenerate.error().code, ErrorCode::kInvalidMesh);
  EXPECT_NE(degenerate.error().message.find("NeoHookeanForceField 'liver': tetrahedron 1"), std::string::npos)
      << degenerate.error().message;
  EXPECT_NE(degenerate.error().message.find("degenerate"), std::string::npos);

  const auto out_of_range = Field::make(rest, {{0, 1, 2, 9}}, NeoHookeanConfig{}, "liver");
  ASSERT_FALSE(out_of_range.has_value());
  EXPECT_NE(out_of_range.error().message.find("tetrahedron 0 refers to node 9"), std::string::npos);

  EXPECT_FALSE(Field::make(rest, {}, NeoHookeanConfig{}, "liver").has_value());
}

}  // namespace
}  // namespace hof::mechanics
