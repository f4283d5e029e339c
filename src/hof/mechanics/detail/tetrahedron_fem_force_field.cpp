#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"

#include <fmt/format.h>

#include "hof/mechanics/detail/tet_rest_geometry.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <tuple>

#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/simd_lanes.h"

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

// Per element, three doubles per corner (its rotated scaled gradient c̃, or its force): the
// record of corner entry (4·element + corner) starts at 3·entry. Loads take four doubles,
// the fourth being the next corner's first (ignored: only lanes 0–2 are used), so each
// array ends with a padding of four.
constexpr std::size_t kCornerStride = 3;
constexpr std::size_t kElementStride = 4 * kCornerStride;
constexpr std::size_t kArrayPadding = 4;

// f[n] += Σ of the vectors at 3·entry over node n's entries (lanes 0–2), nodes [first, last).
// The records read by the gathers are scattered over arrays of several megabytes at 40k
// tetrahedra: fetch them this many entries ahead.
constexpr std::int32_t kTetPrefetchAhead = 12;

void gather_corner_vectors(const double* __restrict vectors, const std::int32_t* __restrict starts,
                           const std::int32_t* __restrict entries, std::size_t first, std::size_t last,
                           double* __restrict f) {
  const std::int32_t end = starts[last];
  for (std::size_t n = first; n < last; ++n) {
    simd::Lanes sum = simd::splat(0.0);
    for (std::int32_t k = starts[n]; k < starts[n + 1]; ++k) {
      if (k + kTetPrefetchAhead < end)
        __builtin_prefetch(vectors + kCornerStride * static_cast<std::size_t>(entries[k + kTetPrefetchAhead]));
      sum += simd::load(vectors + kCornerStride * static_cast<std::size_t>(entries[k]));
    }
    f[3 * n] += sum[0];
    f[3 * n + 1] += sum[1];
    f[3 * n + 2] += sum[2];
  }
}

}  // namespace

Lame lame_parameters(double young_modulus_pa, double poisson_ratio) {
  // Standard isotropic relations (e.g. Sadd, "Elasticity", 2009, Table 6.1).
  return {young_modulus_pa * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio)),
          young_modulus_pa / (2.0 * (1.0 + poisson_ratio))};
}

Expected<std::unique_ptr<TetrahedronFemForceField>> TetrahedronFemForceField::make(
    const std::vector<Vec3>& rest_positions, const std::vector<mesh::Tet>& tets, const TetrahedronFemConfig& config,
    std::string name) {
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
  const auto weights =
      element_modulus_weights(config.element_young_modulus_pa, config.young_modulus_pa, tets.size(), who);
  if (!weights) return std::unexpected(weights.error());
  field->elements_.reserve(tets.size());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    auto element = make_element(rest_positions, tets[t], t, (*weights)[t], who);
    if (!element) return std::unexpected(element.error());
    field->elements_.push_back(*element);
  }
  field->index_elements(rest_positions.size());
  return field;
}

Expected<TetrahedronFemForceField::Element> TetrahedronFemForceField::make_element(
    const std::vector<Vec3>& rest_positions, const mesh::Tet& tet, std::size_t index, double modulus_weight,
    const std::string& who) {
  auto rest = tet_rest_geometry(rest_positions, tet, index, who);
  if (!rest) return std::unexpected(rest.error());
  Element e{};
  e.nodes = rest->nodes;
  // The element's modulus as a weight on its volume (see element_modulus_weights).
  e.volume = rest->volume * modulus_weight;
  e.gradients = rest->gradients;
  e.rest_frame_transposed =
      triangle_frame(rest_positions[e.nodes[0]], rest_positions[e.nodes[1]], rest_positions[e.nodes[2]]).transpose();
  return e;
}

// What follows from the elements' list alone (node ids, no geometry): the per-node incidence,
// the SIMD groups (a repacking of the elements' rest data) and the coupled node pairs.
void TetrahedronFemForceField::index_elements(std::size_t node_count) {
  std::vector<std::array<std::int32_t, 4>> node_lists;
  node_lists.reserve(elements_.size());
  for (const Element& e : elements_) node_lists.push_back(e.nodes);
  incidence_ = make_node_incidence<4>(node_lists, node_count);

  // Element groups for the `large` pass.
  const std::size_t element_count = elements_.size();
  groups_.resize((element_count + simd::kLanes - 1) / simd::kLanes);
  for (std::size_t g = 0; g < groups_.size(); ++g) {
    ElementGroup& group = groups_[g];
    for (int lane = 0; lane < simd::kLanes; ++lane) {
      const std::size_t index = simd::kLanes * g + static_cast<std::size_t>(lane);
      const bool padding = index >= element_count;
      const Element& e = elements_[padding ? 0 : index];
      for (int c = 0; c < 4; ++c) group.nodes[c][lane] = e.nodes[c];
      for (int j = 1; j < 4; ++j) {
        const Vec3 local = e.rest_frame_transposed * e.gradients[j];
        for (int q = 0; q < 3; ++q) group.rest_gradients[3 * (j - 1) + q][lane] = local[q];
      }
      group.volume[lane] = padding ? 0.0 : e.volume;
      group.root_volume[lane] = padding ? 0.0 : std::sqrt(e.volume);
    }
  }

  // Node pairs coupled by the elements, each with the corners that couple them.
  struct Term {
    std::int32_t row, col, entry_row, entry_col;
  };
  std::vector<Term> terms;
  terms.reserve(6 * element_count);
  for (std::size_t e = 0; e < element_count; ++e) {
    const auto& n = elements_[e].nodes;
    const auto base = static_cast<std::int32_t>(4 * e);
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        if (n[i] < n[j])
          terms.push_back({n[i], n[j], base + i, base + j});
        else
          terms.push_back({n[j], n[i], base + j, base + i});
      }
    }
  }
  std::sort(terms.begin(), terms.end(), [](const Term& a, const Term& b) {
    return std::tie(a.row, a.col, a.entry_row) < std::tie(b.row, b.col, b.entry_row);
  });
  edge_terms_.reserve(terms.size());
  for (std::size_t t = 0; t < terms.size(); ++t) {
    if (t == 0 || terms[t].row != terms[t - 1].row || terms[t].col != terms[t - 1].col) {
      const auto at = static_cast<std::int32_t>(t);
      edges_.push_back({-1, -1, at, at});
    }
    edge_terms_.push_back({terms[t].entry_row, terms[t].entry_col});
    ++edges_.back().last;
  }
}

Expected<std::unique_ptr<TetrahedronFemForceField>> TetrahedronFemForceField::remade(
    const std::vector<Vec3>& rest_positions, const std::vector<mesh::Tet>& tets,
    const std::vector<std::int32_t>& old_element, const std::vector<std::int32_t>& new_of_old_node,
    const TetrahedronFemConfig& config, std::size_t& rebuilt) const {
  const std::string who = fmt::format("TetrahedronFEMForceField '{}'", name());
  if (tets.empty())
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: the topology has no tetrahedra", who));
  const auto weights =
      element_modulus_weights(config.element_young_modulus_pa, config.young_modulus_pa, tets.size(), who);
  if (!weights) return std::unexpected(weights.error());
  auto field = std::unique_ptr<TetrahedronFemForceField>(new TetrahedronFemForceField());
  field->set_name(name());
  field->config_ = config;
  field->lame_ = lame_;
  field->elements_.reserve(tets.size());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    if (const std::int32_t o = old_element[t]; o >= 0) {
      // Kept: its rest data as it was, its nodes renumbered.
      Element e = elements_[static_cast<std::size_t>(o)];
      for (std::int32_t& n : e.nodes) n = new_of_old_node[static_cast<std::size_t>(n)];
      field->elements_.push_back(e);
      continue;
    }
    auto element = make_element(rest_positions, tets[t], t, (*weights)[t], who);
    if (!element) return std::unexpected(element.error());
    field->elements_.push_back(*element);
    ++rebuilt;
  }
  field->index_elements(rest_positions.size());
  return field;
}

ForceFieldState TetrahedronFemForceField::make_state() const {
  TetrahedronFemState s;
  // Per element corner (padded to whole groups): the rotated scaled gradient c̃ = √V R b, and
  // the corner's elastic force (same layout, see kCornerStride). At rest R = I.
  const std::size_t padded = simd::kLanes * groups_.size();
  s.scaled_gradients.assign(kElementStride * padded + kArrayPadding, 0.0);
  s.corner_forces.assign(kElementStride * padded + kArrayPadding, 0.0);
  for (std::size_t e = 0; e < elements_.size(); ++e) {
    const double root_volume = std::sqrt(elements_[e].volume);
    for (int i = 0; i < 4; ++i) {
      for (int q = 0; q < 3; ++q)
        s.scaled_gradients[kElementStride * e + kCornerStride * i + q] = root_volume * elements_[e].gradients[i][q];
    }
  }
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
  for (EdgeBlocks& edge : edges_) {
    const auto& term = edge_terms_[static_cast<std::size_t>(edge.first)];
    const std::int32_t row = elements_[static_cast<std::size_t>(term[0] >> 2)].nodes[term[0] & 3];
    const std::int32_t col = elements_[static_cast<std::size_t>(term[1] >> 2)].nodes[term[1] & 3];
    edge.slot_ij = static_cast<std::int32_t>(pattern.slot(row, col));
    edge.slot_ji = static_cast<std::int32_t>(pattern.slot(col, row));
  }
  const std::size_t nodes = incidence_.start.size() - 1;
  diagonal_slots_.resize(nodes);
  std::int64_t covered = 0;
  for (std::size_t n = 0; n < nodes; ++n) {
    diagonal_slots_[n] = static_cast<std::int32_t>(pattern.diagonal_slot(static_cast<std::int32_t>(n)));
  }
  covered = static_cast<std::int64_t>(nodes) + 2 * static_cast<std::int64_t>(edges_.size());
  covers_pattern_ = covered == pattern.block_count() && static_cast<std::int32_t>(nodes) == pattern.block_rows();
}

Mat3 TetrahedronFemForceField::rotation(const Element& e, const Mat3& f, const Eigen::VectorXd& x) const {
  switch (config_.method) {
    case FemMethod::kSmall:
      return Mat3::Identity();
    case FemMethod::kLarge:
      return triangle_frame(node(x, e.nodes[0]), node(x, e.nodes[1]), node(x, e.nodes[2])) * e.rest_frame_transposed;
    case FemMethod::kPolar: {
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

// The co-rotational element (Müller et al. 2002; Nesme et al. 2005) in the element's frame:
// with R = G H (G the current QR frame of the first three nodes, H the rest one transposed),
// M = Gᵀ F Hᵀ = Σ_j e'_j b'_jᵀ where e'_j = Gᵀ(x_j − x_0) and b'_j = H b_j. The strain
// ε' = sym(M) − I and stress σ' = λ tr(ε') I + 2μ ε' are those of the unrotated element seen
// in the rest frame (H ε Hᵀ, H σ Hᵀ: the linear isotropic law commutes with rotations), so
// the nodal forces are f_i = −V R σ b_i = −V G σ' b'_i, and the rotated gradients
// R b_i = G b'_i. In the current frame e'_1 = (|e_1|, 0, 0) and e'_2 = (·, ·, 0), which saves
// a third of the products. Four elements per pass, one per lane.
void TetrahedronFemForceField::large_groups(const ElementGroup* __restrict groups, std::size_t begin, std::size_t end,
                                            const double* __restrict xs, double lambda_scalar, double two_mu_scalar,
                                            double* __restrict stiffness_vectors, double* __restrict corner_forces) {
  using simd::Lanes;
  const Lanes lambda = simd::splat(lambda_scalar);
  const Lanes two_mu = simd::splat(two_mu_scalar);
  const Lanes one = simd::splat(1.0);
  for (std::size_t g = begin; g < end; ++g) {
    const ElementGroup& group = groups[g];
    Lanes px[4], py[4], pz[4];
    for (int c = 0; c < 4; ++c) {
      const double* p0 = xs + 3 * static_cast<std::int64_t>(group.nodes[c][0]);
      const double* p1 = xs + 3 * static_cast<std::int64_t>(group.nodes[c][1]);
      const double* p2 = xs + 3 * static_cast<std::int64_t>(group.nodes[c][2]);
      const double* p3 = xs + 3 * static_cast<std::int64_t>(group.nodes[c][3]);
      px[c] = Lanes{p0[0], p1[0], p2[0], p3[0]};
      py[c] = Lanes{p0[1], p1[1], p2[1], p3[1]};
      pz[c] = Lanes{p0[2], p1[2], p2[2], p3[2]};
    }
    const Lanes e1x = px[1] - px[0], e1y = py[1] - py[0], e1z = pz[1] - pz[0];
    const Lanes e2x = px[2] - px[0], e2y = py[2] - py[0], e2z = pz[2] - pz[0];
    const Lanes e3x = px[3] - px[0], e3y = py[3] - py[0], e3z = pz[3] - pz[0];
    // Current frame G = [a b c]: a along e1, c normal to (e1, e2), b = c × a.
    const Lanes length1 = simd::sqrt(e1x * e1x + e1y * e1y + e1z * e1z);
    const Lanes inverse1 = one / length1;
    const Lanes ax = e1x * inverse1, ay = e1y * inverse1, az = e1z * inverse1;
    Lanes cx = ay * e2z - az * e2y, cy = az * e2x - ax * e2z, cz = ax * e2y - ay * e2x;
    const Lanes inverse_c = one / simd::sqrt(cx * cx + cy * cy + cz * cz);
    cx *= inverse_c;
    cy *= inverse_c;
    cz *= inverse_c;
    const Lanes bx = cy * az - cz * ay, by = cz * ax - cx * az, bz = cx * ay - cy * ax;
    // Edge vectors in the frame.
    const Lanes e2a = ax * e2x + ay * e2y + az * e2z, e2b = bx * e2x + by * e2y + bz * e2z;
    const Lanes e3a = ax * e3x + ay * e3y + az * e3z, e3b = bx * e3x + by * e3y + bz * e3z;
    const Lanes e3c = cx * e3x + cy * e3y + cz * e3z;
    Lanes g1[3], g2[3], g3[3];
    for (int q = 0; q < 3; ++q) {
      g1[q] = simd::load(group.rest_gradients[q]);
      g2[q] = simd::load(group.rest_gradients[3 + q]);
      g3[q] = simd::load(group.rest_gradients[6 + q]);
    }
    // M rows: M_0 = |e1| b'_1 + e2a b'_2 + e3a b'_3, M_1 = e2b b'_2 + e3b b'_3, M_2 = e3c b'_3.
    Lanes m[3][3];
    for (int q = 0; q < 3; ++q) {
      m[0][q] = length1 * g1[q] + e2a * g2[q] + e3a * g3[q];
      m[1][q] = e2b * g2[q] + e3b * g3[q];
      m[2][q] = e3c * g3[q];
    }
    const Lanes s00 = m[0][0] - one, s11 = m[1][1] - one, s22 = m[2][2] - one;
    const Lanes pressure = lambda * (s00 + s11 + s22);
    const Lanes half_two_mu = 0.5 * two_mu;
    const Lanes t00 = pressure + two_mu * s00, t11 = pressure + two_mu * s11, t22 = pressure + two_mu * s22;
    const Lanes t01 = half_two_mu * (m[0][1] + m[1][0]);
    const Lanes t02 = half_two_mu * (m[0][2] + m[2][0]);
    const Lanes t12 = half_two_mu * (m[1][2] + m[2][1]);
    const Lanes volume = simd::load(group.volume);
    const Lanes root_volume = simd::load(group.root_volume);
    const Lanes minus_volume = -volume;
    Lanes force[4][3], gradient[4][3];
    for (int q = 0; q < 3; ++q) force[0][q] = gradient[0][q] = simd::splat(0.0);
    const Lanes* rest[3] = {g1, g2, g3};
    for (int j = 0; j < 3; ++j) {
      const Lanes* r = rest[j];
      // σ' b'_j, then −V G (σ' b'_j); √V G b'_j.
      const Lanes s0 = t00 * r[0] + t01 * r[1] + t02 * r[2];
      const Lanes s1 = t01 * r[0] + t11 * r[1] + t12 * r[2];
      const Lanes s2 = t02 * r[0] + t12 * r[1] + t22 * r[2];
      Lanes* f = force[j + 1];
      f[0] = minus_volume * (ax * s0 + bx * s1 + cx * s2);
      f[1] = minus_volume * (ay * s0 + by * s1 + cy * s2);
      f[2] = minus_volume * (az * s0 + bz * s1 + cz * s2);
      Lanes* c = gradient[j + 1];
      c[0] = root_volume * (ax * r[0] + bx * r[1] + cx * r[2]);
      c[1] = root_volume * (ay * r[0] + by * r[1] + cy * r[2]);
      c[2] = root_volume * (az * r[0] + bz * r[1] + cz * r[2]);
      for (int q = 0; q < 3; ++q) {
        force[0][q] -= f[q];
        gradient[0][q] -= c[q];
      }
    }
    // Corner by corner within each element, four doubles at a time: each store's fourth
    // lane is overwritten by the next corner's. The last corner of the group's last element
    // is stored as three doubles: the next double belongs to the next group, which another
    // thread may be writing.
    auto store_group = [](Lanes(&v)[4][3], double* out) {
      Lanes per_corner[4][4];
      for (int i = 0; i < 4; ++i) simd::transpose_xyz(v[i][0], v[i][1], v[i][2], per_corner[i]);
      for (int lane = 0; lane < simd::kLanes; ++lane) {
        double* element = out + kElementStride * static_cast<std::size_t>(lane);
        for (int i = 0; i < 3; ++i) simd::store(element + kCornerStride * i, per_corner[i][lane]);
        if (lane + 1 < simd::kLanes) {
          simd::store(element + 3 * kCornerStride, per_corner[3][lane]);
        } else {
          for (int q = 0; q < 3; ++q) element[3 * kCornerStride + q] = per_corner[3][lane][q];
        }
      }
    };
    store_group(force, corner_forces + kElementStride * simd::kLanes * g);
    store_group(gradient, stiffness_vectors + kElementStride * simd::kLanes * g);
  }
}

void TetrahedronFemForceField::element_pass_large(const Eigen::VectorXd& x, TetrahedronFemState& state) const {
  double* stiffness_vectors = state.scaled_gradients.data();
  double* corner_forces = state.corner_forces.data();
  parallel_chunks(
      groups_.size(), 16,
      [&](std::size_t begin, std::size_t end) {
        large_groups(groups_.data(), begin, end, x.data(), lame_.lambda, 2.0 * lame_.mu, stiffness_vectors,
                     corner_forces);
      },
      /*min_parallel=*/64);
}

// Linear law in the element's unrotated frame: ε = sym(RᵀF) − I, σ = λ tr(ε) I + 2μ ε; the
// nodal forces are f_i = −V R σ b_i, returned as the map −V R σ (and R).
Mat3 TetrahedronFemForceField::element_force_map(const Element& e, const Eigen::VectorXd& x, Mat3& r) const {
  const Mat3 deformation = deformation_gradient(e, x);
  r = rotation(e, deformation, x);
  const Mat3 unrotated = r.transpose() * deformation;
  const Mat3 strain = 0.5 * (unrotated + unrotated.transpose()) - Mat3::Identity();
  const Mat3 stress = lame_.lambda * strain.trace() * Mat3::Identity() + 2.0 * lame_.mu * strain;
  return -e.volume * (r * stress);
}

// Any rotation (small: R = I; polar), one element at a time, same outputs.
void TetrahedronFemForceField::element_pass_general(const Eigen::VectorXd& x, TetrahedronFemState& state) const {
  double* stiffness_vectors = state.scaled_gradients.data();
  double* corner_forces = state.corner_forces.data();
  parallel_chunks(
      elements_.size(), 64,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t index = begin; index < end; ++index) {
          const Element& e = elements_[index];
          Mat3 r;
          const Mat3 force_map = element_force_map(e, x, r);
          const double root_volume = std::sqrt(e.volume);
          for (int i = 0; i < 4; ++i) {
            Eigen::Map<Vec3>(corner_forces + kElementStride * index + kCornerStride * i) = force_map * e.gradients[i];
            Eigen::Map<Vec3>(stiffness_vectors + kElementStride * index + kCornerStride * i) =
                root_volume * (r * e.gradients[i]);
          }
        }
      },
      /*min_parallel=*/256);
}

// The elements touching the set, each once, evaluated as element_pass_general does (any
// rotation method: `large` takes the same QR frame as the SIMD pass, so the sums agree to
// round-off), their corners' forces summed where the corner is in the set.
bool TetrahedronFemForceField::add_force_sum_on(const Eigen::VectorXd& x, const Eigen::VectorXd& /*v*/,
                                                std::span<const std::int32_t> nodes,
                                                std::span<const std::uint8_t> in_set,
                                                std::vector<std::int32_t>& scratch, Vec3& total) const {
  scratch.clear();
  for (const std::int32_t n : nodes) {
    for (const std::int32_t entry : incidence_.of(static_cast<std::size_t>(n))) scratch.push_back(entry >> 2);
  }
  std::sort(scratch.begin(), scratch.end());
  scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
  for (const std::int32_t index : scratch) {
    const Element& e = elements_[static_cast<std::size_t>(index)];
    Mat3 r;
    const Mat3 force_map = element_force_map(e, x, r);
    for (int i = 0; i < 4; ++i) {
      if (in_set[static_cast<std::size_t>(e.nodes[i])] != 0) total += force_map * e.gradients[i];
    }
  }
  return true;
}

void TetrahedronFemForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& /*v*/,
                                         ForceFieldState& field_state, Eigen::VectorXd& f) const {
  TetrahedronFemState& state = std::get<TetrahedronFemState>(field_state);
  if (config_.method == FemMethod::kLarge)
    element_pass_large(x, state);
  else
    element_pass_general(x, state);
  // Node pass: each node gathers its corners' forces over its elements, in a fixed order.
  const double* corner_forces = state.corner_forces.data();
  parallel_chunks(
      incidence_.start.size() - 1, 128,
      [&](std::size_t begin, std::size_t end) {
        gather_corner_vectors(corner_forces, incidence_.start.data(), incidence_.entries.data(), begin, end, f.data());
      },
      /*min_parallel=*/512);
}

// Stiffness blocks from the rotated scaled gradients c̃ = √V R b of the last force pass:
// K_ij = Σ_e λ c̃_i c̃_jᵀ + μ c̃_j c̃_iᵀ + μ (c̃_i · c̃_j) I (the element stiffness of the
// linear law, rotated: R K_e Rᵀ, Müller et al. 2002), Σ over the elements sharing nodes i
// and j. With A = Σ c̃_i c̃_jᵀ that is K_ij = λA + μAᵀ + μ tr(A) I, and K_ji = K_ijᵀ: one
// 3x3 sum per node pair, three multiply-adds per element, gives both blocks. Each block is
// summed in registers and written once: (i, j), i < j, by edge; then, when this field sets
// the whole matrix, (j, i) and the diagonal by a pass over the rows (complete_from_upper),
// otherwise (j, i) by edge and the diagonal by node. Rows never share a writer: no atomics,
// and a fixed summation order.
namespace {

// A's columns a0..a2 (lane 3 zero) to the blocks λA + μAᵀ + μ tr(A) I at slot_ij and its
// transpose at slot_ji (when ≥ 0).
template <StiffnessTarget kTarget>
void write_pair(BlockSparseMatrix& k, simd::Lanes a0, simd::Lanes a1, simd::Lanes a2, double lambda, double mu,
                std::int64_t slot_ij, std::int64_t slot_ji) {
  using simd::Lanes;
  // Lane 3 of the sums holds products of the neighbouring record's values: clear it, the
  // blocks' padding stays zero.
  a0 = simd::clear_lane3(a0);
  a1 = simd::clear_lane3(a1);
  a2 = simd::clear_lane3(a2);
  Lanes at[4];
  simd::transpose_xyz(a0, a1, a2, at);
  const double d = mu * (a0[0] + a1[1] + a2[2]);
  const Lanes d0{d, 0.0, 0.0, 0.0}, d1{0.0, d, 0.0, 0.0}, d2{0.0, 0.0, d, 0.0};
  write_block<kTarget>(k, slot_ij, lambda * a0 + mu * at[0] + d0, lambda * a1 + mu * at[1] + d1,
                       lambda * a2 + mu * at[2] + d2);
  // Setting the whole matrix, the lower half is completed from the upper one afterwards
  // (BlockSparseMatrix::complete_from_upper): written here it would be a scattered write.
  if (kTarget == StiffnessTarget::kAddDouble && slot_ji >= 0) {
    write_block<kTarget>(k, slot_ji, lambda * at[0] + mu * a0 + d0, lambda * at[1] + mu * a1 + d1,
                         lambda * at[2] + mu * a2 + d2);
  }
}

// The loops below are functions of their own with plain pointers, so that the compiler
// keeps their addresses in registers (inside the task-loop lambdas it spilled them).

// Diagonal blocks of nodes [first, last): A = Σ c̃ c̃ᵀ over the node's corners.
template <StiffnessTarget kTarget>
void fill_diagonal_blocks(const double* __restrict c, const std::int32_t* __restrict starts,
                          const std::int32_t* __restrict entries, const std::int32_t* __restrict slots,
                          std::size_t first, std::size_t last, double lambda, double mu, BlockSparseMatrix& k) {
  using simd::Lanes;
  const std::int32_t end = starts[last];
  for (std::size_t n = first; n < last; ++n) {
    Lanes a0 = simd::splat(0.0), a1 = a0, a2 = a0;
    for (std::int32_t at = starts[n]; at < starts[n + 1]; ++at) {
      if (at + kTetPrefetchAhead < end)
        __builtin_prefetch(c + kCornerStride * static_cast<std::size_t>(entries[at + kTetPrefetchAhead]));
      const double* pi = c + kCornerStride * static_cast<std::size_t>(entries[at]);
      const Lanes ci = simd::load(pi);
      a0 += ci * simd::broadcast(pi);
      a1 += ci * simd::broadcast(pi + 1);
      a2 += ci * simd::broadcast(pi + 2);
    }
    write_pair<kTarget>(k, a0, a1, a2, lambda, mu, slots[n], -1);
  }
}

// Off-diagonal block pairs of edges [first, last): A = Σ c̃_i c̃_jᵀ over the shared elements.
template <StiffnessTarget kTarget, class Edge>
void fill_edge_blocks(const double* __restrict c, const Edge* __restrict edges,
                      const std::array<std::int32_t, 2>* __restrict terms, std::size_t first, std::size_t last,
                      double lambda, double mu, BlockSparseMatrix& k) {
  using simd::Lanes;
  const std::int32_t end = last > first ? edges[last - 1].last : 0;
  for (std::size_t index = first; index < last; ++index) {
    const Edge& edge = edges[index];
    Lanes a0 = simd::splat(0.0), a1 = a0, a2 = a0;
    for (std::int32_t t = edge.first; t < edge.last; ++t) {
      if (t + kTetPrefetchAhead < end) {
        // Both corners' records are in the same element's 96 bytes: two lines at most.
        const double* ahead = c + kCornerStride * static_cast<std::size_t>(terms[t + kTetPrefetchAhead][0] & ~3);
        __builtin_prefetch(ahead);
        __builtin_prefetch(ahead + 8);
      }
      const double* pi = c + kCornerStride * static_cast<std::size_t>(terms[t][0]);
      const double* pj = c + kCornerStride * static_cast<std::size_t>(terms[t][1]);
      const Lanes ci = simd::load(pi);
      a0 += ci * simd::broadcast(pj);
      a1 += ci * simd::broadcast(pj + 1);
      a2 += ci * simd::broadcast(pj + 2);
    }
    write_pair<kTarget>(k, a0, a1, a2, lambda, mu, edge.slot_ij, edge.slot_ji);
  }
}

}  // namespace

template <StiffnessTarget kTarget>
void TetrahedronFemForceField::write_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  const double* c = std::get<TetrahedronFemState>(state).scaled_gradients.data();
  const double lambda = scale * lame_.lambda;
  const double mu = scale * lame_.mu;
  parallel_chunks(
      edges_.size(), 512,
      [&](std::size_t begin, std::size_t end) {
        fill_edge_blocks<kTarget>(c, edges_.data(), edge_terms_.data(), begin, end, lambda, mu, k);
      },
      /*min_parallel=*/1024);
  // Lower half and diagonal. Each element's stiffness leaves rigid translations unloaded
  // (Σ_j c̃_j = 0, so Σ_j A_ij = 0 and K_ii = −Σ_{j≠i} K_ij): when this field sets the whole
  // matrix, one stream over the rows mirrors the upper blocks and sets the diagonal to minus
  // the rest of the row. Added to another field's values it is gathered from the elements.
  parallel_chunks(
      diagonal_slots_.size(), 128,
      [&](std::size_t begin, std::size_t end) {
        if constexpr (kTarget == StiffnessTarget::kSetSingle) {
          k.complete_from_upper_single(begin, end);
        } else if constexpr (kTarget == StiffnessTarget::kSetDouble) {
          k.complete_from_upper(begin, end);
        } else {
          fill_diagonal_blocks<kTarget>(c, incidence_.start.data(), incidence_.entries.data(), diagonal_slots_.data(),
                                        begin, end, lambda, mu, k);
        }
      },
      /*min_parallel=*/512);
}

void TetrahedronFemForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  write_stiffness<StiffnessTarget::kAddDouble>(state, scale, k);
}

bool TetrahedronFemForceField::set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  if (!covers_pattern_) return false;
  write_stiffness<StiffnessTarget::kSetDouble>(state, scale, k);
  return true;
}

bool TetrahedronFemForceField::set_stiffness_single(const ForceFieldState& state, double scale,
                                                    BlockSparseMatrix& k) const {
  if (!covers_pattern_) return false;
  write_stiffness<StiffnessTarget::kSetSingle>(state, scale, k);
  return true;
}

double TetrahedronFemForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState& /*state*/) const {
  double energy = 0.0;
  for (std::size_t index = 0; index < elements_.size(); ++index) {
    const Element& e = elements_[index];
    const Mat3 deformation = deformation_gradient(e, x);
    const Mat3 r = rotation(e, deformation, x);
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
