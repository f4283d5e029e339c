#include "hof/mechanics/detail/neo_hookean_force_field.h"

#include <fmt/format.h>

#include "hof/mechanics/detail/tet_rest_geometry.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace hof::mechanics {

namespace {

using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec9 = Eigen::Matrix<double, 9, 1>;

// Singular values below this (90 % compression along one axis, or inversion) leave the
// Neo-Hookean law: ln σ is continued linearly below it, so the 1/σ of the stress is evaluated
// at σ̂ = max(σ, kMinSingularValue). This is the clamping of Irving, Teran & Fedkiw, "Invertible
// finite elements for robust simulation of large deformation" (SCA 2004, sec. 5), written as
// an extension of the energy so that forces stay its exact gradient everywhere.
constexpr double kMinSingularValue = 0.1;

// F = U diag(σ) Vᵀ with U, V proper rotations. σ is sorted by decreasing magnitude; when
// det F < 0 the last (smallest) singular value is negative (Irving et al. 2004, sec. 4).
struct SignedSvd {
  Mat3 u;
  Vec3 sigma;
  Mat3 v;
};

SignedSvd signed_svd(const Mat3& f) {
  const Eigen::JacobiSVD<Mat3> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
  SignedSvd d{svd.matrixU(), svd.singularValues(), svd.matrixV()};
  if (d.u.determinant() < 0.0) {
    d.u.col(2) *= -1.0;
    d.sigma(2) *= -1.0;
  }
  if (d.v.determinant() < 0.0) {
    d.v.col(2) *= -1.0;
    d.sigma(2) *= -1.0;
  }
  return d;
}

// g(σ): ln σ above the threshold, its tangent line ln c + (σ − c)/c below; g' = 1/max(σ, c),
// g'' = −1/σ² above and 0 below. g is C¹, finite for every finite σ (also σ ≤ 0).
double extended_log(double s) {
  return s >= kMinSingularValue ? std::log(s)
                                : std::log(kMinSingularValue) + (s - kMinSingularValue) / kMinSingularValue;
}
double extended_log_slope(double s) { return 1.0 / std::max(s, kMinSingularValue); }
double extended_log_curvature(double s) { return s >= kMinSingularValue ? -1.0 / (s * s) : 0.0; }

// (g'(a) − g'(b)) / (a − b), without dividing by a small a − b.
double slope_divided_difference(double a, double b) {
  const double hi = std::max(a, b);
  const double lo = std::min(a, b);
  if (lo >= kMinSingularValue) return -1.0 / (a * b);
  if (hi <= kMinSingularValue) return 0.0;
  // One on each side of c: (1/hi − 1/c) / (hi − lo) with 0 < hi − c ≤ hi − lo.
  return -(hi - kMinSingularValue) / (kMinSingularValue * hi * (hi - lo));
}

// (g'(a) + g'(b)) / (a + b). For signed singular values a + b ≥ 0; it reaches 0 only when the
// smallest pair is ±s, where the energy has a kink (Irving et al. 2004): the denominator is
// kept at or above the threshold there (Teran et al. 2005, sec. 5).
double slope_sum_quotient(double a, double b) {
  if (std::min(a, b) >= kMinSingularValue) return 1.0 / (a * b);
  return (extended_log_slope(a) + extended_log_slope(b)) / std::max(a + b, kMinSingularValue);
}

// The compressible Neo-Hookean law as a function of the signed singular values σ of F:
//   Ŵ(σ) = μ/2 (Σ σ_k² − 3) − μ L + λ/2 L²,  L = Σ g(σ_k)  (= ln J when all σ_k ≥ c),
//   P̂_k = ∂Ŵ/∂σ_k = μ σ_k + (λ L − μ) g'(σ_k).
// Above the threshold this is exactly W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)² with
// P = U P̂ Vᵀ = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ.
struct DiagonalLaw {
  double lambda;
  double mu;

  [[nodiscard]] double log_volume(const Vec3& s) const {
    return extended_log(s(0)) + extended_log(s(1)) + extended_log(s(2));
  }

  [[nodiscard]] double energy(const Vec3& s) const {
    const double l = log_volume(s);
    return 0.5 * mu * (s.squaredNorm() - 3.0) - mu * l + 0.5 * lambda * l * l;
  }

  [[nodiscard]] Vec3 stress(const Vec3& s) const {
    const double c = lambda * log_volume(s) - mu;
    return {mu * s(0) + c * extended_log_slope(s(0)), mu * s(1) + c * extended_log_slope(s(1)),
            mu * s(2) + c * extended_log_slope(s(2))};
  }

  [[nodiscard]] Mat3 first_piola(const SignedSvd& d) const {
    return d.u * stress(d.sigma).asDiagonal() * d.v.transpose();
  }

  // dP/dF as a 9x9 matrix on column-major vec(F) (entry (k,l) of F at k + 3l), projected to
  // positive semi-definite. Following Teran, Sifakis, Irving & Fedkiw, "Robust quasistatic
  // finite elements and flesh simulation" (SCA 2005, sec. 4-5), the tangent of an isotropic
  // law at F = U Σ Vᵀ splits into nine modes vec(U M Vᵀ): the 3x3 block ∂P̂/∂σ on the
  // diagonal modes M = diag(e) and, for each pair i < j, the "flip" mode (E_ij + E_ji)/√2
  // with eigenvalue (P̂_i − P̂_j)/(σ_i − σ_j) and the "twist" mode (E_ij − E_ji)/√2 with
  // eigenvalue (P̂_i + P̂_j)/(σ_i + σ_j). Negative eigenvalues are set to zero; the
  // quotients are evaluated in closed form, so equal singular values need no special case.
  [[nodiscard]] Mat9 tangent(const SignedSvd& d) const {
    const Vec3& s = d.sigma;
    const Vec3 slope(extended_log_slope(s(0)), extended_log_slope(s(1)), extended_log_slope(s(2)));
    const double c = lambda * log_volume(s) - mu;

    Mat9 t = Mat9::Zero();
    // Adds value · w wᵀ with w = vec(U M Vᵀ), as (√value w)(√value w)ᵀ so t stays exactly
    // symmetric.
    auto add_mode = [&](double value, const Mat3& m) {
      if (!(value > 0.0)) return;
      const Mat3 w = d.u * m * d.v.transpose();
      const Vec9 sw = std::sqrt(value) * Eigen::Map<const Vec9>(w.data());
      t.noalias() += sw * sw.transpose();
    };

    // ∂P̂_k/∂σ_l = δ_kl (μ + (λL − μ) g''(σ_k)) + λ g'(σ_k) g'(σ_l).
    Mat3 a = lambda * slope * slope.transpose();
    for (int k = 0; k < 3; ++k) a(k, k) += mu + c * extended_log_curvature(s(k));
    const Eigen::SelfAdjointEigenSolver<Mat3> eigen(a);
    for (int k = 0; k < 3; ++k) {
      const Mat3 m = eigen.eigenvectors().col(k).asDiagonal();
      add_mode(eigen.eigenvalues()(k), m);
    }

    const double half_sqrt2 = std::sqrt(0.5);
    constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (const auto& pair : kPairs) {
      const int i = pair[0];
      const int j = pair[1];
      Mat3 m = Mat3::Zero();
      m(i, j) = half_sqrt2;
      m(j, i) = half_sqrt2;
      add_mode(mu + c * slope_divided_difference(s(i), s(j)), m);
      m(j, i) = -half_sqrt2;
      add_mode(mu + c * slope_sum_quotient(s(i), s(j)), m);
    }
    return t;
  }
};

}  // namespace

Expected<std::unique_ptr<NeoHookeanForceField>> NeoHookeanForceField::make(const std::vector<Vec3>& rest_positions,
                                                                           const std::vector<mesh::Tet>& tets,
                                                                           const NeoHookeanConfig& config,
                                                                           std::string name) {
  const std::string who = fmt::format("NeoHookeanForceField '{}'", name);
  if (!(config.young_modulus_pa > 0.0) || !std::isfinite(config.young_modulus_pa)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: youngModulus must be > 0 Pa, got {}", who, config.young_modulus_pa));
  }
  if (!(config.poisson_ratio > -1.0 && config.poisson_ratio < 0.5)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: poissonRatio must be in (-1, 0.5), got {}", who, config.poisson_ratio));
  }
  if (tets.empty()) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: the topology has no tetrahedra", who));
  }
  auto field = std::unique_ptr<NeoHookeanForceField>(new NeoHookeanForceField());
  field->set_name(std::move(name));
  field->config_ = config;
  const Lame lame = lame_parameters(config.young_modulus_pa, config.poisson_ratio);
  field->lambda_ = lame.lambda;
  field->mu_ = lame.mu;
  const auto weights =
      element_modulus_weights(config.element_young_modulus_pa, config.young_modulus_pa, tets.size(), who);
  if (!weights) return std::unexpected(weights.error());
  field->elements_.reserve(tets.size());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    auto rest = tet_rest_geometry(rest_positions, tets[t], t, who);
    if (!rest) return std::unexpected(rest.error());
    Element e{};
    e.nodes = rest->nodes;
    // The element's modulus as a weight on its volume (see element_modulus_weights).
    e.volume = rest->volume * (*weights)[t];
    e.gradients = rest->gradients;
    e.slots.fill(-1);
    field->elements_.push_back(e);
  }
  std::vector<std::array<std::int32_t, 4>> node_lists;
  node_lists.reserve(field->elements_.size());
  for (const Element& e : field->elements_) node_lists.push_back(e.nodes);
  field->coloring_ = color_elements<4>(node_lists, rest_positions.size());
  return field;
}

ForceFieldState NeoHookeanForceField::make_state() const {
  // Tangents start at the rest state, so add_stiffness before any add_force is meaningful.
  NeoHookeanState s;
  const DiagonalLaw law{lambda_, mu_};
  s.tangents.assign(elements_.size(), law.tangent(signed_svd(Mat3::Identity())));
  return s;
}

void NeoHookeanForceField::collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const {
  for (const Element& e : elements_) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) pairs.emplace_back(e.nodes[i], e.nodes[j]);
    }
  }
}

void NeoHookeanForceField::bind(const BlockSparseMatrix& pattern) {
  for (Element& e : elements_) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) e.slots[4 * i + j] = static_cast<std::int32_t>(pattern.slot(e.nodes[i], e.nodes[j]));
    }
  }
}

void NeoHookeanForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& /*v*/, ForceFieldState& state,
                                     Eigen::VectorXd& f) const {
  const DiagonalLaw law{lambda_, mu_};
  // A state not made by make_state() is sized here once (the only allocation).
  std::vector<Mat9>& tangents = std::get<NeoHookeanState>(state).tangents;
  if (tangents.size() != elements_.size()) tangents.resize(elements_.size());
  coloring_.for_each([&](std::int32_t index) {
    const Element& e = elements_[index];
    // Stress from the rotation-preserving SVD (invertible FEM), nodal forces f_i = −V P b_i,
    // and the projected tangent for add_stiffness.
    const SignedSvd d = signed_svd(deformation_gradient(e, x));
    const Mat3 vp = -e.volume * law.first_piola(d);
    tangents[index] = law.tangent(d);
    for (int i = 0; i < 4; ++i) f.segment<3>(3 * static_cast<Eigen::Index>(e.nodes[i])) += vp * e.gradients[i];
  });
}

void NeoHookeanForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  double* values = k.values();
  const std::vector<Mat9>& tangents = std::get<NeoHookeanState>(state).tangents;
  coloring_.for_each([&](std::int32_t index) {
    const Element& e = elements_[index];
    const Mat9& t = tangents[index];
    // K_ij(k,p) = V Σ_{l,n} b_i[l] (∂P_kl/∂F_pn) b_j[n], from F = Σ x_j b_jᵀ. First
    // m_j(r,p) = Σ_n T(r, p + 3n) b_j[n] (9x3), then K_ij = V Σ_l b_i[l] m_j(rows 3l..3l+2).
    std::array<Eigen::Matrix<double, 9, 3>, 4> m;
    for (int j = 0; j < 4; ++j) {
      const Vec3& b = e.gradients[j];
      m[j] = t.middleCols<3>(0) * b(0) + t.middleCols<3>(3) * b(1) + t.middleCols<3>(6) * b(2);
    }
    const double w = scale * e.volume;
    auto block_at = [&](int i, int j) {
      return BlockSparseMatrix::BlockRef(values + BlockSparseMatrix::kBlockStride *
                                                      static_cast<std::int64_t>(e.slots[4 * i + j]));
    };
    // T is symmetric, so K_ji = K_ijᵀ: compute i ≤ j and mirror, keeping K exactly symmetric.
    for (int i = 0; i < 4; ++i) {
      const Vec3& b = e.gradients[i];
      for (int j = i; j < 4; ++j) {
        Mat3 kij = w * (m[j].middleRows<3>(0) * b(0) + m[j].middleRows<3>(3) * b(1) + m[j].middleRows<3>(6) * b(2));
        if (i == j) {
          block_at(i, i) += 0.5 * (kij + kij.transpose());
        } else {
          block_at(i, j) += kij;
          block_at(j, i) += kij.transpose();
        }
      }
    }
  });
}

double NeoHookeanForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState& /*state*/) const {
  const DiagonalLaw law{lambda_, mu_};
  double energy = 0.0;
  for (const Element& e : elements_) energy += e.volume * law.energy(signed_svd(deformation_gradient(e, x)).sigma);
  return energy;
}

Mat3 NeoHookeanForceField::first_piola_stress(const Mat3& f) const {
  return DiagonalLaw{lambda_, mu_}.first_piola(signed_svd(f));
}

double NeoHookeanForceField::energy_density(const Mat3& f) const {
  return DiagonalLaw{lambda_, mu_}.energy(signed_svd(f).sigma);
}

}  // namespace hof::mechanics
