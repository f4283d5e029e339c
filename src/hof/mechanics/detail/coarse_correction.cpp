#include "hof/mechanics/detail/coarse_correction.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "hof/mechanics/detail/linear_solve.h"

namespace hof::mechanics::detail {

namespace {

// About this many nodes per aggregate, and at most this many aggregates: the coarse solve
// (two triangular solves of 6G unknowns) then costs less than a tenth of a product with A on
// the medium liver, and each aggregate holds enough nodes for its six rigid motions to be
// independent.
constexpr double kNodesPerAggregate = 80.0;
constexpr std::int32_t kMaxAggregates = 40;
// An aggregate with fewer nodes than this joins its nearest larger neighbour.
constexpr std::int32_t kMinNodesPerAggregate = 8;

using Rows3x6 = Eigen::Matrix<double, 3, 6>;

// Node i's rows of P: [I | −[arm]×], the translations and rotations of its aggregate, with
// held degrees of freedom left out (their rows zero).
Rows3x6 rigid_rows(const MechanicalModel& model, const CoarseSpace& coarse, std::size_t i) {
  const Eigen::Vector3d& d = coarse.arm[i];
  Rows3x6 p;
  p << 1, 0, 0, 0, d.z(), -d.y(),  //
      0, 1, 0, -d.z(), 0, d.x(),   //
      0, 0, 1, d.y(), -d.x(), 0;
  for (int axis = 0; axis < 3; ++axis) {
    if (model.fixed_dof_mask[3 * i + static_cast<std::size_t>(axis)]) p.row(axis).setZero();
  }
  return p;
}

}  // namespace

void prepare_coarse_space(const MechanicalModel& model, CoarseSpace& coarse, std::size_t chunks) {
  coarse.aggregates = 0;
  coarse.built_step = -1;
  coarse.usable = false;
  const std::size_t nodes = model.node_count();
  if (nodes == 0) return;
  const auto wanted = std::clamp<std::int32_t>(
      static_cast<std::int32_t>(std::lround(static_cast<double>(nodes) / kNodesPerAggregate)), 1, kMaxAggregates);
  Eigen::Vector3d lo = model.rest_positions.front(), hi = lo;
  for (const Eigen::Vector3d& p : model.rest_positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d extent = (hi - lo).cwiseMax(1e-9);
  // Grid cells over the rest shape: the cell size is adjusted until about `wanted` cells hold
  // nodes (an organ fills only part of its box).
  double cell = std::cbrt(extent.prod() / wanted);
  std::map<std::array<std::int64_t, 3>, std::int32_t> cells;
  std::vector<std::int32_t> cell_of(nodes);
  auto bin = [&](double size) {
    cells.clear();
    for (std::size_t i = 0; i < nodes; ++i) {
      const Eigen::Vector3d q = (model.rest_positions[i] - lo) / size;
      const std::array<std::int64_t, 3> key{static_cast<std::int64_t>(q.x()), static_cast<std::int64_t>(q.y()),
                                            static_cast<std::int64_t>(q.z())};
      auto [it, inserted] = cells.try_emplace(key, static_cast<std::int32_t>(cells.size()));
      cell_of[i] = it->second;
    }
  };
  for (int attempt = 0; attempt < 8; ++attempt) {
    bin(cell);
    const double ratio = static_cast<double>(cells.size()) / wanted;
    if (ratio > 0.8 && ratio < 1.25) break;
    cell *= std::cbrt(ratio);
  }
  // Small cells join the nearest cell that is large enough (by centre).
  const auto count = static_cast<std::int32_t>(cells.size());
  std::vector<std::int32_t> members(static_cast<std::size_t>(count), 0);
  std::vector<Eigen::Vector3d> centre(static_cast<std::size_t>(count), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < nodes; ++i) {
    ++members[static_cast<std::size_t>(cell_of[i])];
    centre[static_cast<std::size_t>(cell_of[i])] += model.rest_positions[i];
  }
  for (std::int32_t c = 0; c < count; ++c) centre[static_cast<std::size_t>(c)] /= members[static_cast<std::size_t>(c)];
  std::vector<std::int32_t> target(static_cast<std::size_t>(count), -1);
  std::int32_t kept = 0;
  const std::int32_t largest = *std::max_element(members.begin(), members.end());
  const std::int32_t minimum = std::min(kMinNodesPerAggregate, largest);
  for (std::int32_t c = 0; c < count; ++c) {
    if (members[static_cast<std::size_t>(c)] >= minimum) target[static_cast<std::size_t>(c)] = kept++;
  }
  for (std::int32_t c = 0; c < count; ++c) {
    if (target[static_cast<std::size_t>(c)] >= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    std::int32_t nearest = 0;
    for (std::int32_t k = 0; k < count; ++k) {
      if (members[static_cast<std::size_t>(k)] < minimum) continue;
      const double d2 = (centre[static_cast<std::size_t>(k)] - centre[static_cast<std::size_t>(c)]).squaredNorm();
      if (d2 < best) {
        best = d2;
        nearest = k;
      }
    }
    target[static_cast<std::size_t>(c)] = target[static_cast<std::size_t>(nearest)];
  }
  coarse.aggregates = kept;
  coarse.aggregate.resize(nodes);
  for (std::size_t i = 0; i < nodes; ++i) coarse.aggregate[i] = target[static_cast<std::size_t>(cell_of[i])];
  const auto g = static_cast<std::size_t>(kept);
  coarse.arm.assign(nodes, Eigen::Vector3d::Zero());
  coarse.centre.assign(g, Eigen::Vector3d::Zero());
  coarse.size.assign(g, 0.0);
  coarse.members.assign(g, 0);
  const Eigen::Index n = 6 * static_cast<Eigen::Index>(kept);
  coarse.matrix = Eigen::MatrixXd::Zero(n, n);
  coarse.factor = Eigen::LLT<Eigen::MatrixXd>(n);
  coarse.solution = Eigen::VectorXd::Zero(n);
  coarse.partials.assign(chunks * static_cast<std::size_t>(n), 0.0);
}

bool build_coarse_space(const MechanicalModel& model, MechanicalState& state) {
  CoarseSpace& coarse = state.work->coarse;
  coarse.usable = false;
  coarse.built_step = state.steps;
  if (coarse.aggregates == 0) return false;
  const std::size_t nodes = model.node_count();
  const auto g = static_cast<std::size_t>(coarse.aggregates);
  // The rigid motions about each aggregate's current centre, lengths over its size (so the
  // six columns have comparable scales).
  std::fill(coarse.centre.begin(), coarse.centre.end(), Eigen::Vector3d::Zero());
  std::fill(coarse.size.begin(), coarse.size.end(), 0.0);
  std::fill(coarse.members.begin(), coarse.members.end(), 0);
  for (std::size_t i = 0; i < nodes; ++i) {
    const auto a = static_cast<std::size_t>(coarse.aggregate[i]);
    coarse.centre[a] += state.position(static_cast<std::int32_t>(i));
    ++coarse.members[a];
  }
  for (std::size_t a = 0; a < g; ++a) coarse.centre[a] /= std::max(coarse.members[a], 1);
  for (std::size_t i = 0; i < nodes; ++i) {
    const auto a = static_cast<std::size_t>(coarse.aggregate[i]);
    coarse.arm[i] = state.position(static_cast<std::int32_t>(i)) - coarse.centre[a];
    coarse.size[a] = std::max(coarse.size[a], coarse.arm[i].cwiseAbs().maxCoeff());
  }
  for (std::size_t i = 0; i < nodes; ++i) {
    const double size = coarse.size[static_cast<std::size_t>(coarse.aggregate[i])];
    coarse.arm[i] /= size > 0.0 ? size : 1.0;
  }
  if (!coarse.arm.empty() &&
      !std::all_of(coarse.arm.begin(), coarse.arm.end(), [](const Eigen::Vector3d& d) { return d.allFinite(); })) {
    return false;
  }

  // Pᵀ A P, block by block: (Pᵢᵀ Aᵢⱼ Pⱼ) into the aggregates' 6x6 block.
  const BlockSparseMatrix& a = state.work->system;
  const bool single = uses_single_precision(model);
  Eigen::MatrixXd& m = coarse.matrix;
  m.setZero();
  const auto& row_start = a.row_start();
  const auto& columns = a.columns();
  for (std::size_t i = 0; i < nodes; ++i) {
    const Rows3x6 pi = rigid_rows(model, coarse, i);
    const Eigen::Index ai = 6 * static_cast<Eigen::Index>(coarse.aggregate[i]);
    for (std::int64_t s = row_start[i]; s < row_start[i + 1]; ++s) {
      const auto j = static_cast<std::size_t>(columns[static_cast<std::size_t>(s)]);
      Eigen::Matrix3d block;
      if (single) {
        const float* values = a.single_block(s);
        for (int q = 0; q < 3; ++q) {
          for (int r = 0; r < 3; ++r)
            block(r, q) = static_cast<double>(values[BlockSparseMatrix::kSingleColumnStride * q + r]);
        }
      } else {
        block = a.block(s);
      }
      const Rows3x6 aj = block * rigid_rows(model, coarse, j);
      const Eigen::Index bj = 6 * static_cast<Eigen::Index>(coarse.aggregate[j]);
      m.block<6, 6>(ai, bj).noalias() += pi.transpose() * aj;
    }
  }
  // Symmetric by construction up to rounding; a mode that no free node carries (an aggregate
  // of held nodes) is an identity row, and a tiny shift keeps a nearly dependent one
  // (an aggregate of nearly coplanar nodes) factorable.
  for (Eigen::Index col = 0; col < m.cols(); ++col) {
    for (Eigen::Index row = 0; row < col; ++row) m(row, col) = m(col, row) = 0.5 * (m(row, col) + m(col, row));
  }
  const double largest = m.diagonal().cwiseAbs().maxCoeff();
  if (!std::isfinite(largest) || !(largest > 0.0)) return false;
  for (Eigen::Index k = 0; k < m.rows(); ++k) {
    if (!(m(k, k) > 1e-12 * largest)) {
      m.row(k).setZero();
      m.col(k).setZero();
      m(k, k) = largest;
    }
    m(k, k) += 1e-10 * largest;
  }
  coarse.factor.compute(m);
  coarse.usable = coarse.factor.info() == Eigen::Success;
  return coarse.usable;
}

void restrict_to_coarse(const MechanicalModel& model, const CoarseSpace& coarse, const double* r, std::size_t first,
                        std::size_t last, double* coarse_rhs) {
  for (std::size_t i = first; i < last; ++i) {
    Eigen::Vector3d ri(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
    for (int axis = 0; axis < 3; ++axis) {
      if (model.fixed_dof_mask[3 * i + static_cast<std::size_t>(axis)]) ri[axis] = 0.0;
    }
    // Pᵢᵀ rᵢ = (rᵢ, armᵢ × rᵢ).
    const Eigen::Vector3d moment = coarse.arm[i].cross(ri);
    double* out = coarse_rhs + 6 * static_cast<std::size_t>(coarse.aggregate[i]);
    for (int k = 0; k < 3; ++k) {
      out[k] += ri[k];
      out[3 + k] += moment[k];
    }
  }
}

void prolong_from_coarse(const MechanicalModel& model, const CoarseSpace& coarse, const double* y, std::size_t first,
                         std::size_t last, double* z) {
  for (std::size_t i = first; i < last; ++i) {
    const double* yi = y + 6 * static_cast<std::size_t>(coarse.aggregate[i]);
    // Pᵢ y = translation + rotation × armᵢ.
    const Eigen::Vector3d motion =
        Eigen::Vector3d(yi[0], yi[1], yi[2]) + Eigen::Vector3d(yi[3], yi[4], yi[5]).cross(coarse.arm[i]);
    for (int axis = 0; axis < 3; ++axis) {
      if (!model.fixed_dof_mask[3 * i + static_cast<std::size_t>(axis)])
        z[3 * i + static_cast<std::size_t>(axis)] += motion[axis];
    }
  }
}

}  // namespace hof::mechanics::detail
