#include "hof/mechanics/tetrahedron_fem_force_field.h"

#include <fmt/format.h>

#include "hof/mechanics/tet_rest_geometry.h"

#include <Eigen/SVD>
#include <cmath>

#include "hof/mechanics/parallel.h"

namespace hof::mechanics {

namespace {

// Orthonormal frame of the triangle (p0, p1, p2): first axis along p1−p0, third normal to the
// triangle. Columns are the axes.
Mat3 triangle_frame(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 a = (p1 - p0).normalized();
  const Vec3 c = a.cross(p2 - p0).normalized();
  Mat3 frame;
  frame.col(0) = a;
  frame.col(1) = c.cross(a);
  frame.col(2) = c;
  return frame;
}

}  // namespace

Lame lame_parameters(double young_modulus_pa, double poisson_ratio) {
  // Standard isotropic relations (e.g. Sadd, "Elasticity", 2009, Table 6.1).
  return {young_modulus_pa * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio)),
          young_modulus_pa / (2.0 * (1.0 + poisson_ratio))};
}

Expected<std::unique_ptr<TetrahedronFemForceField>> TetrahedronFemForceField::make(
    const std::vector<Vec3>& rest_positions, const std::vector<mesh::Tet>& tets,
    const TetrahedronFemConfig& config, std::string name) {
  const std::string who = fmt::format("TetrahedronFEMForceField '{}'", name);
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
  auto field = std::unique_ptr<TetrahedronFemForceField>(new TetrahedronFemForceField());
  field->set_name(std::move(name));
  field->config_ = config;
  field->lame_ = lame_parameters(config.young_modulus_pa, config.poisson_ratio);
  field->elements_.reserve(tets.size());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    auto rest = tet_rest_geometry(rest_positions, tets[t], t, who);
    if (!rest) return std::unexpected(rest.error());
    Element e{};
    e.nodes = rest->nodes;
    e.volume = rest->volume;
    e.gradients = rest->gradients;
    e.rest_frame_transposed =
        triangle_frame(rest_positions[e.nodes[0]], rest_positions[e.nodes[1]], rest_positions[e.nodes[2]]).transpose();
    field->elements_.push_back(e);
  }
  std::vector<std::array<std::int32_t, 4>> node_lists;
  node_lists.reserve(field->elements_.size());
  for (const Element& e : field->elements_) node_lists.push_back(e.nodes);
  field->incidence_ = make_node_incidence<4>(node_lists, rest_positions.size());
  field->incidences_.reserve(field->incidence_.entries.size());
  for (std::int32_t entry : field->incidence_.entries) {
    const Element& e = field->elements_[static_cast<std::size_t>(entry >> 2)];
    const int i = entry & 3;
    Incidence inc{};
    inc.gradient = e.gradients[i];
    inc.lambda_volume = field->lame_.lambda * e.volume;
    inc.mu_volume = field->lame_.mu * e.volume;
    for (int j = 0; j < 4; ++j) inc.mu_dots[j] = inc.mu_volume * e.gradients[i].dot(e.gradients[j]);
    inc.slots.fill(-1);
    inc.element = entry >> 2;
    inc.corner = i;
    field->incidences_.push_back(inc);
  }
  return field;
}

ForceFieldState TetrahedronFemForceField::make_state() const {
  ForceFieldState s;
  s.rotations.assign(elements_.size(), Mat3::Identity());
  s.element_matrices.assign(elements_.size(), Mat3::Zero());  // −V R σ per element
  s.element_scalars.assign(16 * elements_.size(), 0.0);       // c_i = R b_i, padded to 4
  return s;
}

void TetrahedronFemForceField::collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const {
  for (const Element& e : elements_) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) pairs.emplace_back(e.nodes[i], e.nodes[j]);
    }
  }
}

void TetrahedronFemForceField::bind(const BlockSparseMatrix& pattern) {
  for (Incidence& inc : incidences_) {
    const Element& e = elements_[static_cast<std::size_t>(inc.element)];
    for (int j = 0; j < 4; ++j) {
      inc.slots[j] = static_cast<std::int32_t>(pattern.slot(e.nodes[inc.corner], e.nodes[j]));
    }
  }
}

Mat3 TetrahedronFemForceField::rotation(const Element& e, const Mat3& f, const Eigen::VectorXd& x,
                                        Eigen::Quaterniond& warm_start) const {
  switch (config_.method) {
    case FemMethod::kSmall:
      return Mat3::Identity();
    case FemMethod::kLarge:
      return triangle_frame(node(x, e.nodes[0]), node(x, e.nodes[1]), node(x, e.nodes[2])) * e.rest_frame_transposed;
    case FemMethod::kPolar: {
      (void)warm_start;
      // Polar decomposition F = R S by Higham's scaled Newton iteration
      // X ← ½(γX + X⁻ᵀ/γ), γ = (‖X⁻¹‖_F/‖X‖_F)^½ (Higham, "Computing the polar decomposition
      // with applications", SIAM J. Sci. Stat. Comput. 7(4), 1986): quadratic convergence,
      // five or six iterations from F for any element shape. Inverted or flat elements
      // (det F ≤ 0) have no rotation in their polar factor: take R from the SVD with the
      // sign fixed to a proper rotation instead.
      const double det = f.determinant();
      if (det > 1e-9 * std::max(1e-300, f.squaredNorm() * f.norm())) {
        Mat3 r = f;
        for (int iteration = 0; iteration < 12; ++iteration) {
          const Mat3 inverse = r.inverse();
          const double gamma = std::sqrt(inverse.norm() / r.norm());
          const Mat3 next = 0.5 * (gamma * r + inverse.transpose() / gamma);
          const double change = (next - r).squaredNorm();
          r = next;
          if (change < 3e-24) break;
        }
        return r;
      }
      const Eigen::JacobiSVD<Mat3> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Mat3 u = svd.matrixU();
      if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
      return u * svd.matrixV().transpose();
    }
  }
  return Mat3::Identity();
}

void TetrahedronFemForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& /*v*/,
                                         ForceFieldState& state, Eigen::VectorXd& f) const {
  const double lambda = lame_.lambda;
  const double mu = lame_.mu;
  // Element pass: rotation and the stress term −V R σ of each element, independently.
  parallel_chunks(
      elements_.size(), 64,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t index = begin; index < end; ++index) {
          const Element& e = elements_[index];
          const Mat3 deformation = deformation_gradient(e, x);
          Eigen::Quaterniond unused = Eigen::Quaterniond::Identity();
          const Mat3 r = rotation(e, deformation, x, unused);
          state.rotations[index] = r;
          // Linear law in the element's unrotated frame: ε = sym(RᵀF) − I,
          // σ = λ tr(ε) I + 2μ ε; nodal forces f_i = −V R σ b_i.
          const Mat3 unrotated = r.transpose() * deformation;
          const Mat3 strain = 0.5 * (unrotated + unrotated.transpose()) - Mat3::Identity();
          const Mat3 stress = lambda * strain.trace() * Mat3::Identity() + 2.0 * mu * strain;
          state.element_matrices[index].noalias() = -e.volume * (r * stress);
          // Rotated gradients for the stiffness, padded to four lanes for the row pass.
          double* c = state.element_scalars.data() + 16 * index;
          for (int i = 0; i < 4; ++i) {
            const Vec3 ci = r * e.gradients[i];
            c[4 * i] = ci.x();
            c[4 * i + 1] = ci.y();
            c[4 * i + 2] = ci.z();
            c[4 * i + 3] = 0.0;
          }
        }
      },
      /*min_parallel=*/256);
  // Node pass: each node gathers f_i = Σ (−V R σ) b_i over its elements, in a fixed order.
  // The element terms are the only random reads: fetch them a few incidences ahead.
  constexpr std::int32_t kAhead = 6;
  parallel_chunks(
      incidence_.start.size() - 1, 128,
      [&](std::size_t begin, std::size_t end) {
        const std::int32_t last = incidence_.start[end];
        for (std::size_t n = begin; n < end; ++n) {
          Vec3 sum = Vec3::Zero();
          for (std::int32_t k = incidence_.start[n]; k < incidence_.start[n + 1]; ++k) {
            if (k + kAhead < last) __builtin_prefetch(&state.element_matrices[incidences_[k + kAhead].element]);
            const Incidence& inc = incidences_[k];
            sum.noalias() += state.element_matrices[inc.element] * inc.gradient;
          }
          f.segment<3>(3 * static_cast<Eigen::Index>(n)) += sum;
        }
      },
      /*min_parallel=*/512);
}

void TetrahedronFemForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  double* values = k.values();
  const double* rotated = state.element_scalars.data();
  // Row pass: each block row (node i) gathers, from every element using node i, the rotated
  // element stiffness blocks R K_e Rᵀ (i, j) = V (λ c_i c_jᵀ + μ c_j c_iᵀ + μ (b_i·b_j) I)
  // with c = R b. One thread per row: no write conflicts, fixed summation order. Blocks are
  // stored as padded columns, so column q gets λV c_i c_j[q] + μV c_j c_i[q] in four lanes.
  constexpr std::int32_t kAhead = 6;
  parallel_chunks(
      incidence_.start.size() - 1, 64,
      [&](std::size_t begin, std::size_t end) {
        const std::int32_t last = incidence_.start[end];
        for (std::int32_t at = incidence_.start[begin]; at < last; ++at) {
          if (at + kAhead < last) {
            const double* ahead = rotated + 16 * static_cast<std::int64_t>(incidences_[at + kAhead].element);
            __builtin_prefetch(ahead);
            __builtin_prefetch(ahead + 8);
          }
          const Incidence& inc = incidences_[at];
          const double* c = rotated + 16 * static_cast<std::int64_t>(inc.element);
          const Eigen::Map<const Eigen::Vector4d> ci(c + 4 * inc.corner);
          const Eigen::Vector4d wl_ci = (scale * inc.lambda_volume) * ci;
          const Eigen::Vector3d wm_ci = (scale * inc.mu_volume) * ci.head<3>();
          for (int j = 0; j < 4; ++j) {
            const Eigen::Map<const Eigen::Vector4d> cj(c + 4 * j);
            double* block = values + BlockSparseMatrix::kBlockStride * inc.slots[j];
            for (int q = 0; q < 3; ++q) {
              Eigen::Map<Eigen::Vector4d>(block + 4 * q) += wl_ci * cj[q] + cj * wm_ci[q];
            }
            const double diagonal = scale * inc.mu_dots[j];
            block[0] += diagonal;
            block[5] += diagonal;
            block[10] += diagonal;
          }
        }
      },
      /*min_parallel=*/256);
}

double TetrahedronFemForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState& /*state*/) const {
  double energy = 0.0;
  for (std::size_t index = 0; index < elements_.size(); ++index) {
    const Element& e = elements_[index];
    const Mat3 deformation = deformation_gradient(e, x);
    Eigen::Quaterniond unused = Eigen::Quaterniond::Identity();
    const Mat3 r = rotation(e, deformation, x, unused);
    const Mat3 unrotated = r.transpose() * deformation;
    const Mat3 strain = 0.5 * (unrotated + unrotated.transpose()) - Mat3::Identity();
    // W = μ ε:ε + λ/2 (tr ε)² per unit volume.
    energy += e.volume * (lame_.mu * strain.squaredNorm() + 0.5 * lame_.lambda * strain.trace() * strain.trace());
  }
  return energy;
}

std::int64_t TetrahedronFemForceField::find_invalid_element(const Eigen::VectorXd& x) const {
  // Linear elements have no defence against inversion: once inside out they push the wrong
  // way. Co-rotational elements recover, so only `small` reports.
  if (config_.method != FemMethod::kSmall) return -1;
  for (std::size_t index = 0; index < elements_.size(); ++index) {
    if (!(deformation_gradient(elements_[index], x).determinant() > 0.0)) return static_cast<std::int64_t>(index);
  }
  return -1;
}

}  // namespace hof::mechanics
