#include "hof/mechanics/detail/triangle_fem_force_field.h"

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "hof/mechanics/detail/tet_rest_geometry.h"

namespace hof::mechanics {

namespace {

// The in-plane frame of a triangle: x along the first edge, y in the plane towards the third
// corner (the QR frame of the edges; Nesme et al., EG 2005). Invalid (zero) for a degenerate one.
Eigen::Matrix<double, 3, 2> plane_frame(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 e1 = p1 - p0;
  const Vec3 normal = e1.cross(p2 - p0);
  Eigen::Matrix<double, 3, 2> r = Eigen::Matrix<double, 3, 2>::Zero();
  const double edge = e1.norm(), area2 = normal.norm();
  if (!(edge > 0.0) || !(area2 > 0.0)) return r;
  r.col(0) = e1 / edge;
  r.col(1) = (normal / area2).cross(r.col(0));
  return r;
}

// Elasticity matrix D of a linear isotropic membrane (Voigt order xx, yy, 2xy): plane stress
// E/(1−ν²)[1 ν 0; ν 1 0; 0 0 (1−ν)/2], or plane strain E/((1+ν)(1−2ν))[1−ν ν 0; ν 1−ν 0;
// 0 0 (1−2ν)/2] (Zienkiewicz & Taylor, "The Finite Element Method", vol. 1, §6.2).
Eigen::Matrix3d elasticity(double e, double nu, bool plane_strain) {
  Eigen::Matrix3d d = Eigen::Matrix3d::Zero();
  if (plane_strain) {
    const double c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    d << 1.0 - nu, nu, 0.0, nu, 1.0 - nu, 0.0, 0.0, 0.0, 0.5 * (1.0 - 2.0 * nu);
    return c * d;
  }
  const double c = e / (1.0 - nu * nu);
  d << 1.0, nu, 0.0, nu, 1.0, 0.0, 0.0, 0.0, 0.5 * (1.0 - nu);
  return c * d;
}

}  // namespace

Expected<std::unique_ptr<TriangleFemForceField>> TriangleFemForceField::make(const std::vector<Vec3>& rest_positions,
                                                                             const std::vector<mesh::Tri>& triangles,
                                                                             const TriangleFemConfig& config,
                                                                             std::string name) {
  const std::string who = fmt::format("{} '{}'", config.sofa_type, name);
  auto bad = [&](std::string what) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: {}", who, what));
  };
  if (triangles.empty()) return bad("no triangles (give the node a triangle topology)");
  if (!(config.young_modulus_pa > 0.0) || !std::isfinite(config.young_modulus_pa)) {
    return bad(fmt::format("youngModulus must be > 0 Pa, got {}", config.young_modulus_pa));
  }
  auto valid_nu = [](double nu) { return nu > -1.0 && nu < 0.5; };
  if (!valid_nu(config.poisson_ratio))
    return bad(fmt::format("poissonRatio must be in (-1, 0.5), got {}", config.poisson_ratio));
  if (!(config.rest_scale > 0.0 && config.rest_scale <= 2.0))
    return bad(fmt::format("restScale must be in (0, 2], got {}", config.rest_scale));
  if (!(config.thickness_m > 0.0) || !std::isfinite(config.thickness_m)) {
    return bad(fmt::format("thickness must be > 0, got {}", config.thickness_m));
  }
  const auto weights =
      element_modulus_weights(config.element_young_modulus_pa, config.young_modulus_pa, triangles.size(), who);
  if (!weights) return std::unexpected(weights.error());
  if (!config.element_poisson_ratio.empty()) {
    if (config.element_poisson_ratio.size() != triangles.size()) {
      return bad(fmt::format("poissonRatio has {} values for {} triangles (give one, or one per triangle)",
                             config.element_poisson_ratio.size(), triangles.size()));
    }
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const double nu = config.element_poisson_ratio[t];
      if (nu != 0.0 && !valid_nu(nu))
        return bad(fmt::format("poissonRatio of triangle {} must be in (-1, 0.5), got {}", t, nu));
    }
  }

  auto field = std::unique_ptr<TriangleFemForceField>(new TriangleFemForceField());
  field->set_name(std::move(name));
  field->config_ = config;
  if (field->config_.method == FemMethod::kPolar) field->config_.method = FemMethod::kLarge;
  field->elements_.reserve(triangles.size());
  const auto n = static_cast<std::int32_t>(rest_positions.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const mesh::Tri& tri = triangles[t];
    for (std::int32_t i : tri) {
      if (i < 0 || i >= n) return bad(fmt::format("triangle {} refers to node {} of {}", t, i, n));
    }
    Element e{};
    e.nodes = {tri[0], tri[1], tri[2]};
    const Vec3& p0 = rest_positions[static_cast<std::size_t>(tri[0])];
    const Vec3& p1 = rest_positions[static_cast<std::size_t>(tri[1])];
    const Vec3& p2 = rest_positions[static_cast<std::size_t>(tri[2])];
    e.rest_frame = plane_frame(p0, p1, p2);
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    if (e.rest_frame.isZero() || !(area > 1e-14 * std::max(1e-30, (p1 - p0).squaredNorm() + (p2 - p0).squaredNorm()))) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("{}: triangle {} (nodes {} {} {}) is degenerate at rest (zero area)", who, t,
                                    tri[0], tri[1], tri[2]));
    }
    e.rest_origin = p0;
    e.rest[0] = Eigen::Vector2d::Zero();
    e.rest[1] = config.rest_scale * e.rest_frame.transpose() * (p1 - p0);
    e.rest[2] = config.rest_scale * e.rest_frame.transpose() * (p2 - p0);
    // Linear shape functions: ∇N_1, ∇N_2 are the rows of Dm⁻¹ with Dm = [r1 r2]; ∇N_0 = −∇N_1 − ∇N_2.
    Eigen::Matrix2d dm;
    dm.col(0) = e.rest[1];
    dm.col(1) = e.rest[2];
    const Eigen::Matrix2d inv = dm.inverse();
    std::array<Eigen::Vector2d, 3> grad;
    grad[1] = inv.row(0).transpose();
    grad[2] = inv.row(1).transpose();
    grad[0] = -grad[1] - grad[2];
    // Strain–displacement matrix B (Voigt: ε_xx, ε_yy, γ_xy).
    Eigen::Matrix<double, 3, 6> b = Eigen::Matrix<double, 3, 6>::Zero();
    for (int i = 0; i < 3; ++i) {
      b(0, 2 * i) = grad[static_cast<std::size_t>(i)].x();
      b(1, 2 * i + 1) = grad[static_cast<std::size_t>(i)].y();
      b(2, 2 * i) = grad[static_cast<std::size_t>(i)].y();
      b(2, 2 * i + 1) = grad[static_cast<std::size_t>(i)].x();
    }
    const double young = config.young_modulus_pa * (*weights)[t];
    const double nu = config.element_poisson_ratio.empty() || config.element_poisson_ratio[t] == 0.0
                          ? config.poisson_ratio
                          : config.element_poisson_ratio[t];
    // K_e = t A Bᵀ D B: the constant-strain triangle (Turner et al. 1956; Zienkiewicz & Taylor §6.2).
    // On the rest shape (scaled by restScale).
    // The initial-stress term: the nodal forces (rest-shape gradients, t·A of the rest shape)
    // turn with the element as it lies, whose edges are 1/restScale of the rest ones.
    e.gradients = grad;
    e.thickness_area = config.thickness_m * area * config.rest_scale * config.rest_scale * config.rest_scale;
    e.stress = elasticity(young, nu, config.plane_strain) * b;
    e.stiffness = config.thickness_m * area * config.rest_scale * config.rest_scale * b.transpose() *
                  elasticity(young, nu, config.plane_strain) * b;
    field->elements_.push_back(e);
  }
  return field;
}

ForceFieldState TriangleFemForceField::make_state() const {
  MembraneState s;
  s.frames.assign(elements_.size(), Mat3::Zero());
  s.voigt_stress.assign(3 * elements_.size(), 0.0);
  for (std::size_t t = 0; t < elements_.size(); ++t) s.frames[t].leftCols<2>() = elements_[t].rest_frame;
  return s;
}

void TriangleFemForceField::collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const {
  for (const Element& e : elements_) {
    for (int a = 0; a < 3; ++a) {
      for (int b = a + 1; b < 3; ++b)
        pairs.emplace_back(e.nodes[static_cast<std::size_t>(a)], e.nodes[static_cast<std::size_t>(b)]);
    }
  }
}

void TriangleFemForceField::bind(const BlockSparseMatrix& pattern) {
  for (Element& e : elements_) {
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t b = 0; b < 3; ++b)
        e.slots[3 * a + b] = static_cast<std::int32_t>(pattern.slot(e.nodes[a], e.nodes[b]));
    }
  }
}

TriangleFemForceField::Frame TriangleFemForceField::frame(const Element& e, const Eigen::VectorXd& x) const {
  if (config_.method == FemMethod::kSmall) return e.rest_frame;
  const Frame r = plane_frame(node(x, e.nodes[0]), node(x, e.nodes[1]), node(x, e.nodes[2]));
  // A triangle collapsed to a line has no plane: keep the rest frame rather than produce NaN.
  return r.isZero() ? e.rest_frame : r;
}

Eigen::Matrix<double, 6, 1> TriangleFemForceField::displacement(const Element& e, const Frame& r,
                                                                const Eigen::VectorXd& x) const {
  // Large: corner 0 is the frame's origin; small: the rest frame and origin stay fixed.
  const Vec3 origin = config_.method == FemMethod::kSmall ? e.rest_origin : node(x, e.nodes[0]);
  Eigen::Matrix<double, 6, 1> u;
  for (std::size_t i = 0; i < 3; ++i) {
    u.segment<2>(static_cast<Eigen::Index>(2 * i)) = r.transpose() * (node(x, e.nodes[i]) - origin) - e.rest[i];
  }
  return u;
}

void TriangleFemForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd&, ForceFieldState& state,
                                      Eigen::VectorXd& f) const {
  MembraneState& membrane = std::get<MembraneState>(state);
  for (std::size_t t = 0; t < elements_.size(); ++t) {
    const Element& e = elements_[t];
    const Frame r = frame(e, x);
    membrane.frames[t].leftCols<2>() = r;
    const Eigen::Matrix<double, 6, 1> u = displacement(e, r, x);
    Eigen::Map<Eigen::Vector3d>(membrane.voigt_stress.data() + 3 * t) = e.stress * u;
    const Eigen::Matrix<double, 6, 1> local = -(e.stiffness * u);
    for (std::size_t i = 0; i < 3; ++i) {
      f.segment<3>(3 * static_cast<Eigen::Index>(e.nodes[i])) += r * local.segment<2>(static_cast<Eigen::Index>(2 * i));
    }
  }
}

void TriangleFemForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  // K_ab = R K_e[ab] Rᵀ (the co-rotational stiffness as SOFA assembles it, without the
  // frame's rotation term) plus the tension's initial-stress term.
  const MembraneState& membrane = std::get<MembraneState>(state);
  for (std::size_t t = 0; t < elements_.size(); ++t) {
    const Element& e = elements_[t];
    const Frame r = membrane.frames[t].leftCols<2>();
    // The tension's initial-stress term, its compression clamped at 0 (a slack membrane
    // buckles rather than pushes): σ⁺ from the eigen-decomposition of the 2x2 stress.
    const Eigen::Vector3d voigt = Eigen::Map<const Eigen::Vector3d>(membrane.voigt_stress.data() + 3 * t);
    Eigen::Matrix2d sigma;
    sigma << voigt.x(), voigt.z(), voigt.z(), voigt.y();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig;
    eig.computeDirect(sigma);
    const Eigen::Matrix2d tension =
        eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t b = 0; b < 3; ++b) {
        const Eigen::Matrix2d local =
            e.stiffness.block<2, 2>(static_cast<Eigen::Index>(2 * a), static_cast<Eigen::Index>(2 * b));
        const double geometric = e.thickness_area * e.gradients[a].dot(tension * e.gradients[b]);
        k.block(e.slots[3 * a + b]) += scale * (r * local * r.transpose() + geometric * Mat3::Identity());
      }
    }
  }
}

double TriangleFemForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState&) const {
  double energy = 0.0;
  for (const Element& e : elements_) {
    const Eigen::Matrix<double, 6, 1> u = displacement(e, frame(e, x), x);
    energy += 0.5 * u.dot(e.stiffness * u);
  }
  return energy;
}

}  // namespace hof::mechanics
