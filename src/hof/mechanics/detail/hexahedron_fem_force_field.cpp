#include "hof/mechanics/detail/hexahedron_fem_force_field.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <span>

#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/simd_lanes.h"

namespace hof::mechanics {

namespace {

using Vector24 = Eigen::Matrix<double, 24, 1>;

// The 2×2×2 Gauss points ±1/√3 (weights 1), in Hex corner order.
Vec3 gauss_point(int g) {
  const double a = 1.0 / std::sqrt(3.0);
  const auto& s = mesh::kHexCornerSigns[g];
  return {s[0] * a, s[1] * a, s[2] * a};
}

// Orthonormal frame of a hexahedron given by its corner offsets, as SOFA's `large` method
// (HexahedronFEMForceField::computeRotationLarge): the first axis along the mean of the four
// edges in local x, the third normal to it and the mean of the four edges in local y, the
// second completing the frame. Columns are the axes. Zero when the element is flat.
Mat3 edge_frame(const std::array<Vec3, 8>& p) {
  const Vec3 along_x = (p[1] - p[0]) + (p[2] - p[3]) + (p[5] - p[4]) + (p[6] - p[7]);
  const Vec3 along_y = (p[3] - p[0]) + (p[2] - p[1]) + (p[7] - p[4]) + (p[6] - p[5]);
  const double length = along_x.norm();
  Vec3 normal = along_x.cross(along_y);
  const double normal_length = normal.norm();
  if (!(length > 0.0) || !(normal_length > 1e-12 * length * along_y.norm())) return Mat3::Zero();
  Mat3 frame;
  frame.col(0) = along_x / length;
  frame.col(2) = normal / normal_length;
  frame.col(1) = frame.col(2).cross(frame.col(0));
  return frame;
}

// The element's three averaged edges as columns: the mean of its four edges along local x,
// along y and along z (SOFA's HexahedronFEMForceField::computeRotationPolar, whose rows they
// are). Equal to twice the Jacobian of the trilinear map at the centre.
Mat3 averaged_edges(const std::array<Vec3, 8>& p) {
  const Vec3 along_x = 0.25 * ((p[1] - p[0]) + (p[2] - p[3]) + (p[5] - p[4]) + (p[6] - p[7]));
  const Vec3 along_y = 0.25 * ((p[3] - p[0]) + (p[2] - p[1]) + (p[7] - p[4]) + (p[6] - p[5]));
  const Vec3 along_z = 0.25 * ((p[4] - p[0]) + (p[5] - p[1]) + (p[7] - p[3]) + (p[6] - p[2]));
  Mat3 edges = Mat3::Zero();
  edges << along_x, along_y, along_z;
  return edges;
}

// Rotation of the polar decomposition F = R S by Higham's scaled Newton iteration
// X ← ½(γX + X⁻ᵀ/γ), γ = (‖X⁻¹‖_F/‖X‖_F)^½ (Higham, "Computing the polar decomposition with
// applications", SIAM J. Sci. Stat. Comput. 7(4), 1986). An inverted or flat element
// (det F ≤ 0) has no rotation in its polar factor: R then comes from the SVD, with the sign
// fixed to a proper rotation.
Mat3 polar_rotation(const Mat3& f) {
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

// Jacobian of the trilinear map at ξ for corners p (J_ab = ∂x_a/∂ξ_b).
Mat3 jacobian_at(const std::array<Vec3, 8>& p, const Eigen::Matrix<double, 3, 8>& d) {
  Mat3 j = Mat3::Zero();
  for (int c = 0; c < 8; ++c) j += p[c] * d.col(c).transpose();
  return j;
}

// Validates a per-element list: empty, or one value per hexahedron each passing `valid`
// (0 always means "the uniform value").
template <class Valid>
Expected<void> check_element_list(const std::vector<double>& list, std::size_t hexes, const std::string& who,
                                  const char* parameter, const char* range, const Valid& valid) {
  if (list.empty()) return {};
  if (list.size() != hexes) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: {} has {} values but the topology has {} hexahedra (one per hexahedron, or "
                                  "empty for one value everywhere)",
                                  who, parameter, list.size(), hexes));
  }
  for (std::size_t e = 0; e < list.size(); ++e) {
    if (list[e] != 0.0 && !valid(list[e])) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: {} of hexahedron {} is {}; it must be {} (or 0 for the uniform value)", who,
                                    parameter, e, list[e], range));
    }
  }
  return {};
}

}  // namespace

HexahedronFemForceField::ElementMatrix hex_element_stiffness(const std::array<Vec3, 8>& rest, double lambda, double mu,
                                                             double& min_det) {
  HexahedronFemForceField::ElementMatrix k = HexahedronFemForceField::ElementMatrix::Zero();
  min_det = std::numeric_limits<double>::infinity();
  for (int g = 0; g < 8; ++g) {
    const Eigen::Matrix<double, 3, 8> d = mesh::hex_shape_derivatives(gauss_point(g));
    const Mat3 j = jacobian_at(rest, d);
    const double det = j.determinant();
    min_det = std::min(min_det, det);
    if (!(det > 0.0)) continue;  // the caller refuses the element
    // Physical gradients g_c = J⁻ᵀ ∂N_c/∂ξ.
    const Eigen::Matrix<double, 3, 8> grad = j.transpose().inverse() * d;
    for (int a = 0; a < 8; ++a) {
      for (int b = 0; b < 8; ++b) {
        const Vec3 ga = grad.col(a), gb = grad.col(b);
        k.block<3, 3>(3 * a, 3 * b) +=
            det * (lambda * ga * gb.transpose() + mu * gb * ga.transpose() + mu * ga.dot(gb) * Mat3::Identity());
      }
    }
  }
  return k;
}

Expected<std::unique_ptr<HexahedronFemForceField>> HexahedronFemForceField::make(
    const std::vector<Vec3>& rest_positions, const std::vector<mesh::Hex>& hexes, const HexahedronFemConfig& config,
    std::string name) {
  const std::string who = fmt::format("HexahedronFEMForceField '{}'", name);
  const auto valid_poisson = [](double nu) { return nu > -1.0 && nu < 0.5; };
  const auto valid_young = [](double e) { return e > 0.0 && std::isfinite(e); };
  if (!valid_young(config.young_modulus_pa)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: youngModulus must be > 0 Pa, got {}", who, config.young_modulus_pa));
  }
  if (!valid_poisson(config.poisson_ratio)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: poissonRatio must be in (-1, 0.5), got {}", who, config.poisson_ratio));
  }
  if (hexes.empty()) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: the topology has no hexahedra", who));
  }
  if (auto ok =
          check_element_list(config.element_young_modulus_pa, hexes.size(), who, "youngModulus", "> 0 Pa", valid_young);
      !ok) {
    return std::unexpected(ok.error());
  }
  if (auto ok = check_element_list(config.element_poisson_ratio, hexes.size(), who, "poissonRatio", "in (-1, 0.5)",
                                   valid_poisson);
      !ok) {
    return std::unexpected(ok.error());
  }

  auto field = std::unique_ptr<HexahedronFemForceField>(new HexahedronFemForceField());
  field->set_name(std::move(name));
  field->config_ = config;
  field->node_count_ = rest_positions.size();

  // Elements of the same shape (corner offsets equal to 2⁻⁴⁰ of the model's size, far below
  // round-off of any use) and Poisson ratio share one rest stiffness: every cell of a grid.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& p : rest_positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double model_size = std::max((hi - lo).maxCoeff(), std::numeric_limits<double>::min());
  using ShapeKey = std::array<std::int64_t, 22>;
  std::map<ShapeKey, std::int32_t> shapes;

  field->elements_.reserve(hexes.size());
  for (std::size_t h = 0; h < hexes.size(); ++h) {
    const mesh::Hex& hex = hexes[h];
    const auto describe = [&] {
      return fmt::format("hexahedron {} (nodes {} {} {} {} {} {} {} {})", h, hex[0], hex[1], hex[2], hex[3], hex[4],
                         hex[5], hex[6], hex[7]);
    };
    for (int c = 0; c < 8; ++c) {
      if (hex[c] < 0 || static_cast<std::size_t>(hex[c]) >= rest_positions.size()) {
        return make_error(ErrorCode::kInvalidMesh, fmt::format("{}: {} refers to node {} but the model has {} nodes",
                                                               who, describe(), hex[c], rest_positions.size()));
      }
      for (int d = 0; d < c; ++d) {
        if (hex[d] == hex[c]) {
          return make_error(ErrorCode::kInvalidMesh, fmt::format("{}: {} uses node {} twice", who, describe(), hex[c]));
        }
      }
    }
    Element e{};
    std::array<Vec3, 8> rest{};
    Vec3 centre = Vec3::Zero();
    for (int c = 0; c < 8; ++c) {
      e.nodes[c] = hex[c];
      rest[c] = rest_positions[hex[c]];
      centre += rest[c] / 8.0;
    }
    double extent = 0.0;
    for (int c = 0; c < 8; ++c) {
      e.rest_offsets[c] = rest[c] - centre;
      extent = std::max(extent, e.rest_offsets[c].norm());
    }
    const double element_young = config.element_young_modulus_pa.empty() || config.element_young_modulus_pa[h] == 0.0
                                     ? config.young_modulus_pa
                                     : config.element_young_modulus_pa[h];
    const double element_poisson = config.element_poisson_ratio.empty() || config.element_poisson_ratio[h] == 0.0
                                       ? config.poisson_ratio
                                       : config.element_poisson_ratio[h];
    e.young_modulus_pa = element_young;

    ShapeKey key{};
    for (int c = 1; c < 8; ++c) {
      for (int a = 0; a < 3; ++a) {
        key[static_cast<std::size_t>(3 * (c - 1) + a)] = std::llround((rest[c][a] - rest[0][a]) / model_size * 0x1p40);
      }
    }
    key[21] = std::bit_cast<std::int64_t>(element_poisson);
    const auto found = shapes.find(key);
    if (found != shapes.end()) {
      e.stiffness = found->second;
    } else {
      const Lame unit = lame_parameters(1.0, element_poisson);
      double min_det = 0.0;
      ElementMatrix k = hex_element_stiffness(rest, unit.lambda, unit.mu, min_det);
      // det J ≈ V/8; a determinant this small relative to the element's size is a flat cell.
      if (!(min_det > 1e-10 * extent * extent * extent)) {
        return make_error(ErrorCode::kInvalidMesh,
                          fmt::format("{}: {} is degenerate or inverted at rest: its Jacobian determinant is {:.3g} "
                                      "m^3 at a Gauss point (the corners must follow SOFA's order: 0-3 "
                                      "counter-clockwise around the bottom face seen from above, 4-7 above them)",
                                      who, describe(), min_det));
      }
      e.stiffness = static_cast<std::int32_t>(field->stiffness_.size());
      field->stiffness_.push_back(k);
      // The same matrix as 64 padded column-major blocks (the system matrix's layout).
      for (int block = 0; block < 64; ++block) {
        for (int q = 0; q < 3; ++q) {
          for (int row = 0; row < 3; ++row)
            field->stiffness_lanes_.push_back(k(3 * (block / 8) + row, 3 * (block % 8) + q));
          field->stiffness_lanes_.push_back(0.0);
        }
      }
      shapes.emplace(key, e.stiffness);
    }

    // Rest data of the rotation methods.
    const Mat3 frame = edge_frame(e.rest_offsets);
    e.rest_frame_transposed = frame.transpose();
    e.rest_polar_transposed = polar_rotation(averaged_edges(e.rest_offsets)).transpose();
    field->elements_.push_back(e);
  }

  std::vector<std::array<std::int32_t, 8>> node_lists;
  node_lists.reserve(field->elements_.size());
  for (const Element& e : field->elements_) node_lists.push_back(e.nodes);
  field->coloring_ = color_elements<8>(std::span<const std::array<std::int32_t, 8>>(node_lists), rest_positions.size());
  field->incidence_ =
      make_node_incidence<8>(std::span<const std::array<std::int32_t, 8>>(node_lists), rest_positions.size());
  return field;
}

ForceFieldState HexahedronFemForceField::make_state() const {
  HexahedronFemState s;
  s.rotations.assign(elements_.size(), Mat3::Identity());
  return s;
}

void HexahedronFemForceField::collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const {
  for (const Element& e : elements_) {
    for (int a = 0; a < 8; ++a) {
      for (int b = a + 1; b < 8; ++b) pairs.emplace_back(e.nodes[a], e.nodes[b]);
    }
  }
}

void HexahedronFemForceField::bind(const BlockSparseMatrix& pattern) {
  slots_.resize(elements_.size());
  for (std::size_t index = 0; index < elements_.size(); ++index) {
    const Element& e = elements_[index];
    for (int a = 0; a < 8; ++a) {
      for (int b = 0; b < 8; ++b) {
        slots_[index][static_cast<std::size_t>(8 * a + b)] =
            static_cast<std::int32_t>(pattern.slot(e.nodes[a], e.nodes[b]));
      }
    }
  }
  // Whether the blocks this field writes are the whole pattern (then it may set the matrix).
  std::vector<std::uint8_t> ours(static_cast<std::size_t>(pattern.block_count()), 0);
  for (const auto& element_slots : slots_) {
    for (std::int32_t slot : element_slots) ours[static_cast<std::size_t>(slot)] = 1;
  }
  covers_pattern_ = static_cast<std::size_t>(pattern.block_rows()) == node_count_ &&
                    std::count(ours.begin(), ours.end(), std::uint8_t{1}) == pattern.block_count();
}

std::array<Vec3, 8> HexahedronFemForceField::current_offsets(const Element& e, const Eigen::VectorXd& x) {
  std::array<Vec3, 8> offsets{};
  Vec3 centre = Vec3::Zero();
  for (int c = 0; c < 8; ++c) {
    offsets[c] = x.segment<3>(3 * static_cast<Eigen::Index>(e.nodes[c]));
    centre += offsets[c];
  }
  centre /= 8.0;
  for (Vec3& o : offsets) o -= centre;
  return offsets;
}

Mat3 HexahedronFemForceField::rotation(const Element& e, const std::array<Vec3, 8>& offsets) const {
  // SOFA's polar rotation: that of the averaged edges now, relative to that at rest
  // (HexahedronFEMForceField::initPolar and accumulateForcePolar rotate both the rest and the
  // current corners by the polar factor of their own edge matrix). The edges are not divided
  // by their rest lengths, so for a cell longer on one axis this is not the polar rotation of
  // the deformation gradient: a shear along the long axis turns it less.
  const auto polar = [&] {
    const Mat3 now = polar_rotation(averaged_edges(offsets));
    const Mat3 relative = now * e.rest_polar_transposed;
    return relative;
  };
  switch (config_.method) {
    case FemMethod::kSmall:
      return Mat3::Identity();
    case FemMethod::kLarge: {
      const Mat3 frame = edge_frame(offsets);
      // A flattened element has no edge frame: its polar rotation is the nearest one.
      if (frame.isZero(0.0)) return polar();
      return frame * e.rest_frame_transposed;
    }
    case FemMethod::kPolar:
      return polar();
  }
  return Mat3::Identity();
}

Vector24 HexahedronFemForceField::displacement(const Element& e, const Mat3& r, const std::array<Vec3, 8>& offsets) {
  // K leaves rigid translations unloaded, so displacements are taken about the element's
  // centre (now and at rest): the values stay small even far from the origin.
  Vector24 u;
  for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = r.transpose() * offsets[c] - e.rest_offsets[c];
  return u;
}

void HexahedronFemForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& /*v*/, ForceFieldState& state,
                                        Eigen::VectorXd& f) const {
  std::vector<Mat3>& rotations = std::get<HexahedronFemState>(state).rotations;
  // One colour at a time, its elements in parallel: no two of them share a node, so each adds
  // its corner forces with plain stores, in an order independent of the thread count.
  coloring_.for_each([&](std::int32_t index) {
    const Element& e = elements_[static_cast<std::size_t>(index)];
    const std::array<Vec3, 8> offsets = current_offsets(e, x);
    const Mat3 r = rotation(e, offsets);
    rotations[static_cast<std::size_t>(index)] = r;
    // f = −R K (Rᵀ x − x₀) (Nesme et al. 2005).
    const Vector24 ku =
        e.young_modulus_pa * (stiffness_[static_cast<std::size_t>(e.stiffness)] * displacement(e, r, offsets));
    for (int c = 0; c < 8; ++c) {
      f.segment<3>(3 * static_cast<Eigen::Index>(e.nodes[c])) -= r * ku.segment<3>(3 * c);
    }
  });
}

// The stiffness K_e = R K₀ Rᵀ (Nesme et al. 2005), gathered by block row: each node's row is
// summed from the elements that use it, in element order, by one thread — no colouring, no
// atomics, rows written where they lie in memory, results independent of the thread count.
// A block is three columns of four lanes (the matrix's own layout): M = K₀_ab Rᵀ column by
// column, then R M, six fused multiply-adds of four lanes per column.
//
// Set (this field's couplings are the whole pattern): only the blocks above the diagonal are
// summed, in double precision; BlockSparseMatrix::complete_from_upper then mirrors them below
// and sets each diagonal block to minus the rest of its row (K₀ leaves translations unloaded).
// For the single-precision target the double values serve as the row's scratch and are left
// stale. Add (other fields share the matrix): every block of the row, added to what is there.
namespace {

using simd::Lanes;

// Block (a, b) of s R K₀ Rᵀ, as three columns (lane 3 zero). `scaled_r` holds the columns of
// s R, `r` R itself.
inline void rotated_block(const double* k0_block, const Mat3& r, const Lanes scaled_r[3], bool rotated, double s,
                          Lanes out[3]) {
  const Lanes c0 = simd::load(k0_block), c1 = simd::load(k0_block + 4), c2 = simd::load(k0_block + 8);
  if (!rotated) {
    out[0] = s * c0;
    out[1] = s * c1;
    out[2] = s * c2;
    return;
  }
  for (int j = 0; j < 3; ++j) {
    const Lanes m = c0 * r(j, 0) + c1 * r(j, 1) + c2 * r(j, 2);
    out[j] = scaled_r[0] * m[0] + scaled_r[1] * m[1] + scaled_r[2] * m[2];
  }
}

}  // namespace

template <StiffnessTarget kTarget>
void HexahedronFemForceField::write_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  constexpr bool kSet = kTarget != StiffnessTarget::kAddDouble;
  const bool rotated = config_.method != FemMethod::kSmall;
  const std::vector<Mat3>& rotations = std::get<HexahedronFemState>(state).rotations;
  const auto& row_start = k.row_start();
  parallel_chunks(
      incidence_.start.size() - 1, 64,
      [&](std::size_t first, std::size_t last) {
        for (std::size_t n = first; n < last; ++n) {
          const auto node = static_cast<std::int32_t>(n);
          const std::int64_t diagonal = k.diagonal_slot(node);
          if constexpr (kSet) {
            for (std::int64_t slot = diagonal + 1; slot < row_start[n + 1]; ++slot) {
              std::fill_n(k.values() + BlockSparseMatrix::kBlockStride * slot, BlockSparseMatrix::kBlockStride, 0.0);
            }
          }
          for (const std::int32_t entry : incidence_.of(n)) {
            const auto index = static_cast<std::size_t>(entry >> 3);
            const int a = entry & 7;
            const Element& e = elements_[index];
            const double* k0 = stiffness_lanes_.data() + kLaneMatrixSize * static_cast<std::size_t>(e.stiffness);
            const Mat3& r = rotations[index];
            const double s = scale * e.young_modulus_pa;
            Lanes scaled_r[3];
            for (int q = 0; q < 3; ++q) scaled_r[q] = Lanes{s * r(0, q), s * r(1, q), s * r(2, q), 0.0};
            for (int b = 0; b < 8; ++b) {
              if (kSet && e.nodes[b] <= node) continue;  // the lower half and diagonal come from the upper
              Lanes out[3];
              rotated_block(k0 + BlockSparseMatrix::kBlockStride * (8 * a + b), r, scaled_r, rotated, s, out);
              write_block<StiffnessTarget::kAddDouble>(k, slots_[index][static_cast<std::size_t>(8 * a + b)], out[0],
                                                       out[1], out[2]);
            }
          }
          if constexpr (kTarget == StiffnessTarget::kSetSingle) {
            for (std::int64_t slot = diagonal + 1; slot < row_start[n + 1]; ++slot) {
              const double* block = k.values() + BlockSparseMatrix::kBlockStride * slot;
              write_block<StiffnessTarget::kSetSingle>(k, slot, simd::load(block), simd::load(block + 4),
                                                       simd::load(block + 8));
            }
          }
        }
      },
      /*min_parallel=*/256);
  if constexpr (kSet) {
    parallel_chunks(
        incidence_.start.size() - 1, 128,
        [&](std::size_t first, std::size_t last) {
          if constexpr (kTarget == StiffnessTarget::kSetSingle) {
            k.complete_from_upper_single(first, last);
          } else {
            k.complete_from_upper(first, last);
          }
        },
        /*min_parallel=*/512);
  }
}

void HexahedronFemForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  write_stiffness<StiffnessTarget::kAddDouble>(state, scale, k);
}

bool HexahedronFemForceField::set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  if (!covers_pattern_) return false;
  write_stiffness<StiffnessTarget::kSetDouble>(state, scale, k);
  return true;
}

bool HexahedronFemForceField::set_stiffness_single(const ForceFieldState& state, double scale,
                                                   BlockSparseMatrix& k) const {
  if (!covers_pattern_) return false;
  write_stiffness<StiffnessTarget::kSetSingle>(state, scale, k);
  return true;
}

double HexahedronFemForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState& /*state*/) const {
  // ½ uᵀ K u per element, u the unrotated displacement.
  double energy = 0.0;
  for (const Element& e : elements_) {
    const std::array<Vec3, 8> offsets = current_offsets(e, x);
    const Vector24 u = displacement(e, rotation(e, offsets), offsets);
    energy += 0.5 * e.young_modulus_pa * u.dot(stiffness_[static_cast<std::size_t>(e.stiffness)] * u);
  }
  return energy;
}

std::int64_t HexahedronFemForceField::find_invalid_element(const Eigen::VectorXd& x) const {
  // Linear elements have no defence against inversion: once inside out they push the wrong
  // way. Co-rotational elements recover, so only `small` reports (as the tetrahedral field).
  if (config_.method != FemMethod::kSmall) return -1;
  for (std::size_t index = 0; index < elements_.size(); ++index) {
    const Element& e = elements_[index];
    const std::array<Vec3, 8> offsets = current_offsets(e, x);
    for (int g = 0; g < 8; ++g) {
      if (!(jacobian_at(offsets, mesh::hex_shape_derivatives(gauss_point(g))).determinant() > 0.0)) {
        return static_cast<std::int64_t>(index);
      }
    }
  }
  return -1;
}

HexahedronFemForceField::ElementMatrix HexahedronFemForceField::element_stiffness(std::size_t e) const {
  return elements_[e].young_modulus_pa * stiffness_[static_cast<std::size_t>(elements_[e].stiffness)];
}

}  // namespace hof::mechanics
