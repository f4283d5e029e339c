#include "hof/mechanics/detail/mesh_spring_force_field.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "hof/mechanics/detail/parallel.h"
#include "hof/mechanics/detail/simd_lanes.h"

#include "hof/mesh/boundary.h"

namespace hof::mechanics {

Expected<std::unique_ptr<MeshSpringForceField>> MeshSpringForceField::make(const std::vector<Vec3>& rest_positions,
                                                                           const std::vector<mesh::Tet>& tets,
                                                                           const std::vector<mesh::Tri>& triangles,
                                                                           const MeshSpringConfig& config,
                                                                           std::string name) {
  const std::string who = fmt::format("MeshSpringForceField '{}'", name);
  const auto valid = [](double value) { return value >= 0.0 && std::isfinite(value); };
  // Named as SOFA's data (stiffness, trianglesStiffness, ...).
  const auto check_values = [&](const SpringValues& values, const char* stiffness,
                                const char* damping) -> Expected<void> {
    if (!valid(values.stiffness)) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: {} must be >= 0, got {}", who, stiffness, values.stiffness));
    }
    if (!valid(values.damping)) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: {} must be >= 0, got {}", who, damping, values.damping));
    }
    return {};
  };
  const SpringValues generic{config.stiffness_n_per_m, config.damping_n_s_per_m};
  if (auto ok = check_values(generic, "stiffness", "damping"); !ok) return std::unexpected(ok.error());
  if (config.triangles) {
    if (auto ok = check_values(*config.triangles, "trianglesStiffness", "trianglesDamping"); !ok)
      return std::unexpected(ok.error());
  }
  if (config.tetrahedra) {
    if (auto ok = check_values(*config.tetrahedra, "tetrahedraStiffness", "tetrahedraDamping"); !ok) {
      return std::unexpected(ok.error());
    }
  }
  if (!(config.rest_length_scale > 0.0 && config.rest_length_scale <= 2.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: restLengthScale must be in (0, 2], got {}", who, config.rest_length_scale));
  }
  // The element kinds in SOFA's order (MeshSpringForceField::init: lines, triangles, quads,
  // tetrahedra, cubes; HoF's models have triangles and tetrahedra). A kind whose stiffness
  // and damping are both 0 is skipped there, so its edges take a later kind's values; an edge
  // already given a spring keeps it (MeshSpringForceField::addSpring returns when the pair is
  // in its set). Every kind 0: springs of no effect on all edges, as if there were none.
  struct KindEdges {
    std::vector<mesh::Edge> edges;
    SpringValues values;
  };
  const std::array<KindEdges, 2> kinds = {
      KindEdges{mesh::triangle_edges(triangles), config.triangles.value_or(generic)},
      KindEdges{mesh::tet_edges(tets), config.tetrahedra.value_or(generic)}};
  const bool any_active = std::ranges::any_of(kinds, [](const KindEdges& k) {
    return !k.edges.empty() && (k.values.stiffness != 0.0 || k.values.damping != 0.0);
  });
  // (edge, order of its kind): sorted by edge, the first kind first; the first of each edge kept.
  std::vector<std::pair<mesh::Edge, std::size_t>> claimed;
  for (std::size_t kind = 0; kind < kinds.size(); ++kind) {
    const bool active = kinds[kind].values.stiffness != 0.0 || kinds[kind].values.damping != 0.0;
    if (any_active && !active) continue;
    for (const mesh::Edge& e : kinds[kind].edges) claimed.emplace_back(e, kind);
  }
  std::sort(claimed.begin(), claimed.end());
  claimed.erase(
      std::unique(claimed.begin(), claimed.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
      claimed.end());
  if (claimed.empty())
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: the topology has no edges", who));

  auto field = std::unique_ptr<MeshSpringForceField>(new MeshSpringForceField());
  field->set_name(std::move(name));
  field->exact_tangent_ = config.tangent == SpringTangent::kExact;
  field->springs_.reserve(claimed.size());
  for (const auto& [e, kind] : claimed) {
    if (e[0] < 0 || static_cast<std::size_t>(e[1]) >= rest_positions.size()) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("{}: edge {}-{} refers to a missing node", who, e[0], e[1]));
    }
    const double length = (rest_positions[e[1]] - rest_positions[e[0]]).norm();
    if (!(length > 0.0)) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("{}: nodes {} and {} coincide at rest (zero-length spring)", who, e[0], e[1]));
    }
    // SOFA divides by the edge's length at rest (MeshSpringForceField::addSpring), not by the
    // scaled rest length of HoF's restLengthScale.
    const double per_length = config.rule == SpringStiffnessRule::kDividedByRestLength ? 1.0 / length : 1.0;
    const SpringValues& values = kinds[kind].values;
    field->springs_.push_back({{e[0], e[1]},
                               config.rest_length_scale * length,
                               values.stiffness * per_length,
                               values.damping * per_length,
                               {-1, -1}});
  }
  field->groups_.resize((field->springs_.size() + simd::kLanes - 1) / simd::kLanes);
  for (std::size_t g = 0; g < field->groups_.size(); ++g) {
    for (int lane = 0; lane < simd::kLanes; ++lane) {
      const std::size_t index = simd::kLanes * g + static_cast<std::size_t>(lane);
      const Spring& spring = field->springs_[index < field->springs_.size() ? index : 0];
      field->groups_[g].first[lane] = spring.nodes[0];
      field->groups_[g].second[lane] = spring.nodes[1];
      field->groups_[g].rest_length[lane] = spring.rest_length;
      field->groups_[g].stiffness[lane] = spring.stiffness;
      field->groups_[g].damping[lane] = spring.damping;
    }
  }
  std::vector<std::array<std::int32_t, 2>> node_lists;
  node_lists.reserve(field->springs_.size());
  for (const Spring& s : field->springs_) node_lists.push_back(s.nodes);
  field->incidence_ = make_node_incidence<2>(node_lists, rest_positions.size());
  return field;
}

namespace {

// Per spring (padded to whole groups), 12 doubles: the force on its first node (f, 0), the
// stiffness block K_s = w u uᵀ + t I as (w u, t) and (u, 0).
constexpr std::size_t kRecord = 12;

// The loops below are functions of their own with plain pointers, so that the compiler
// keeps their addresses in registers (inside the task-loop lambdas it spilled them).

// The gathers read records scattered over several megabytes at 40k tetrahedra: fetch them
// this many entries ahead.
constexpr std::int32_t kSpringPrefetchAhead = 12;

// f[n] += Σ ± force on the spring's first node, nodes [first, last).
void gather_spring_forces(const double* __restrict records, const std::int32_t* __restrict starts,
                          const std::int32_t* __restrict entries, std::size_t first, std::size_t last,
                          double* __restrict f) {
  const std::int32_t end = starts[last];
  for (std::size_t n = first; n < last; ++n) {
    simd::Lanes sum = simd::splat(0.0);
    for (std::int32_t at = starts[n]; at < starts[n + 1]; ++at) {
      if (at + kSpringPrefetchAhead < end)
        __builtin_prefetch(records + kRecord * static_cast<std::size_t>(entries[at + kSpringPrefetchAhead] >> 1));
      const std::int32_t entry = entries[at];
      const simd::Lanes force_on_first = simd::load(records + kRecord * static_cast<std::size_t>(entry >> 1));
      if (entry & 1)
        sum -= force_on_first;
      else
        sum += force_on_first;
    }
    f[3 * n] += sum[0];
    f[3 * n + 1] += sum[1];
    f[3 * n + 2] += sum[2];
  }
}

// Adds the columns of w u uᵀ + t I of a record.
inline void add_spring_block(const double* record, simd::Lanes& a0, simd::Lanes& a1, simd::Lanes& a2, double& t) {
  const simd::Lanes wu = simd::load(record + 4);
  a0 += wu * simd::broadcast(record + 8);
  a1 += wu * simd::broadcast(record + 9);
  a2 += wu * simd::broadcast(record + 10);
  t += record[7];
}

template <StiffnessTarget kTarget>
void write_spring_block(BlockSparseMatrix& k, std::int64_t slot, simd::Lanes a0, simd::Lanes a1, simd::Lanes a2,
                        double t, double factor) {
  write_block<kTarget>(k, slot, factor * (a0 + simd::Lanes{t, 0.0, 0.0, 0.0}),
                       factor * (a1 + simd::Lanes{0.0, t, 0.0, 0.0}), factor * (a2 + simd::Lanes{0.0, 0.0, t, 0.0}));
}

template <StiffnessTarget kTarget>
void fill_spring_diagonal(const double* __restrict records, const std::int32_t* __restrict starts,
                          const std::int32_t* __restrict entries, const std::int32_t* __restrict slots,
                          std::size_t first, std::size_t last, double scale, BlockSparseMatrix& k) {
  const std::int32_t end = starts[last];
  for (std::size_t n = first; n < last; ++n) {
    simd::Lanes a0 = simd::splat(0.0), a1 = a0, a2 = a0;
    double t = 0.0;
    for (std::int32_t at = starts[n]; at < starts[n + 1]; ++at) {
      if (at + kSpringPrefetchAhead < end) {
        const double* ahead = records + kRecord * static_cast<std::size_t>(entries[at + kSpringPrefetchAhead] >> 1);
        __builtin_prefetch(ahead + 4);
        __builtin_prefetch(ahead + 11);
      }
      add_spring_block(records + kRecord * static_cast<std::size_t>(entries[at] >> 1), a0, a1, a2, t);
    }
    write_spring_block<kTarget>(k, slots[n], a0, a1, a2, t, scale);
  }
}

template <StiffnessTarget kTarget, class Spring>
void fill_spring_pairs(const double* __restrict records, const Spring* __restrict springs, std::size_t first,
                       std::size_t last, double factor, BlockSparseMatrix& k) {
  for (std::size_t index = first; index < last; ++index) {
    simd::Lanes a0 = simd::splat(0.0), a1 = a0, a2 = a0;
    double t = 0.0;
    add_spring_block(records + kRecord * index, a0, a1, a2, t);
    write_spring_block<kTarget>(k, springs[index].slots[0], a0, a1, a2, t, factor);
    // Setting the whole matrix, the lower half is completed from the upper one afterwards.
    if constexpr (kTarget == StiffnessTarget::kAddDouble) {
      write_spring_block<kTarget>(k, springs[index].slots[1], a0, a1, a2, t, factor);
    }
  }
}

}  // namespace

ForceFieldState MeshSpringForceField::make_state() const {
  SpringState s;
  s.records.assign(kRecord * simd::kLanes * groups_.size(), 0.0);
  return s;
}

void MeshSpringForceField::collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const {
  for (const Spring& s : springs_) pairs.emplace_back(s.nodes[0], s.nodes[1]);
}

void MeshSpringForceField::bind(const BlockSparseMatrix& pattern) {
  for (Spring& s : springs_) {
    // The block above the diagonal first: it is the one written when the springs set the matrix.
    const std::int32_t i = std::min(s.nodes[0], s.nodes[1]);
    const std::int32_t j = std::max(s.nodes[0], s.nodes[1]);
    s.slots = {static_cast<std::int32_t>(pattern.slot(i, j)), static_cast<std::int32_t>(pattern.slot(j, i))};
  }
  const std::size_t nodes = incidence_.start.size() - 1;
  diagonal_slots_.resize(nodes);
  for (std::size_t n = 0; n < nodes; ++n) {
    diagonal_slots_[n] = static_cast<std::int32_t>(pattern.diagonal_slot(static_cast<std::int32_t>(n)));
  }
  covers_pattern_ = static_cast<std::int64_t>(nodes + 2 * springs_.size()) == pattern.block_count() &&
                    static_cast<std::int32_t>(nodes) == pattern.block_rows();
}

void MeshSpringForceField::spring_groups(const SpringGroup* __restrict groups, std::size_t begin, std::size_t end,
                                         const double* __restrict xs, const double* __restrict vs, bool exact_tangent,
                                         double* __restrict records) {
  using simd::Lanes;
  const Lanes zero = simd::splat(0.0);
  for (std::size_t g = begin; g < end; ++g) {
    const SpringGroup& group = groups[g];
    const Lanes k = simd::load(group.stiffness);
    const Lanes c = simd::load(group.damping);
    Lanes d[3], dv[3];
    for (int q = 0; q < 3; ++q) {
      d[q] = Lanes{xs[3 * group.second[0] + q] - xs[3 * group.first[0] + q],
                   xs[3 * group.second[1] + q] - xs[3 * group.first[1] + q],
                   xs[3 * group.second[2] + q] - xs[3 * group.first[2] + q],
                   xs[3 * group.second[3] + q] - xs[3 * group.first[3] + q]};
      dv[q] = Lanes{vs[3 * group.second[0] + q] - vs[3 * group.first[0] + q],
                    vs[3 * group.second[1] + q] - vs[3 * group.first[1] + q],
                    vs[3 * group.second[2] + q] - vs[3 * group.first[2] + q],
                    vs[3 * group.second[3] + q] - vs[3 * group.first[3] + q]};
    }
    const Lanes length = simd::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const auto stretched = length > zero;  // a collapsed spring has no direction
    const Lanes inverse = stretched ? 1.0 / length : zero;
    const Lanes u[3] = {d[0] * inverse, d[1] * inverse, d[2] * inverse};
    const Lanes rest = simd::load(group.rest_length);
    const Lanes tension = k * (length - rest) + c * (dv[0] * u[0] + dv[1] * u[1] + dv[2] * u[2]);
    // −∂f_i/∂x_i = k u uᵀ + k (1 − l0/l)(I − u uᵀ). The transverse term is negative for
    // a compressed spring; it is clamped at zero so that the system matrix stays
    // positive definite (Choi & Ko, "Stable but responsive cloth", SIGGRAPH 2002). SOFA's
    // (exact_tangent) takes the whole tension over the length, the damper's too, unclamped
    // (SpringForceField::computeSpringForce: tgt = forceIntensity / d). A collapsed spring
    // resists equally in all directions (k I).
    const Lanes clamped = k * (1.0 - rest * inverse);
    const Lanes transverse = stretched ? (exact_tangent ? tension * inverse : (clamped > zero ? clamped : zero)) : k;
    const Lanes along = k - transverse;
    Lanes force[4], weighted[4], direction[4];
    simd::transpose_xyz(tension * u[0], tension * u[1], tension * u[2], force);
    simd::transpose_xyz(along * u[0], along * u[1], along * u[2], weighted);
    simd::transpose_xyz(u[0], u[1], u[2], direction);
    double* out = records + kRecord * simd::kLanes * g;
    for (int lane = 0; lane < simd::kLanes; ++lane) {
      double* record = out + kRecord * static_cast<std::size_t>(lane);
      simd::store(record, force[lane]);
      simd::store(record + 4, weighted[lane]);
      record[7] = transverse[lane];
      simd::store(record + 8, direction[lane]);
    }
  }
}

// The springs touching the set, each once, with the spring pass's law.
bool MeshSpringForceField::add_force_sum_on(const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                                            std::span<const std::int32_t> nodes, std::span<const std::uint8_t> in_set,
                                            std::vector<std::int32_t>& scratch, Vec3& total) const {
  scratch.clear();
  for (const std::int32_t n : nodes) {
    for (const std::int32_t entry : incidence_.of(static_cast<std::size_t>(n))) scratch.push_back(entry >> 1);
  }
  std::sort(scratch.begin(), scratch.end());
  scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
  for (const std::int32_t index : scratch) {
    const Spring& spring = springs_[static_cast<std::size_t>(index)];
    const auto first = static_cast<Eigen::Index>(spring.nodes[0]);
    const auto second = static_cast<Eigen::Index>(spring.nodes[1]);
    const Vec3 d = x.segment<3>(3 * second) - x.segment<3>(3 * first);
    const double length = d.norm();
    if (!(length > 0.0)) continue;  // a collapsed spring has no direction (and no force)
    const Vec3 u = d / length;
    const double tension = spring.stiffness * (length - spring.rest_length) +
                           spring.damping * (v.segment<3>(3 * second) - v.segment<3>(3 * first)).dot(u);
    if (in_set[static_cast<std::size_t>(first)] != 0) total += tension * u;
    if (in_set[static_cast<std::size_t>(second)] != 0) total -= tension * u;
  }
  return true;
}

void MeshSpringForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                                     Eigen::VectorXd& f) const {
  const double* xs = x.data();
  const double* vs = v.data();
  double* records = std::get<SpringState>(state).records.data();
  // Spring pass, four springs at a time: tension and stiffness block of each.
  parallel_chunks(
      groups_.size(), 64,
      [&](std::size_t begin, std::size_t end) {
        spring_groups(groups_.data(), begin, end, xs, vs, exact_tangent_, records);
      },
      /*min_parallel=*/256);
  // Node pass: each node gathers its springs' forces in a fixed order.
  parallel_chunks(
      incidence_.start.size() - 1, 256,
      [&](std::size_t begin, std::size_t end) {
        gather_spring_forces(records, incidence_.start.data(), incidence_.entries.data(), begin, end, f.data());
      },
      /*min_parallel=*/1024);
}

// Each spring's off-diagonal pair (i, j), (j, i) is −K_s (symmetric); the diagonal blocks are
// Σ K_s over the node's springs. No atomics, fixed summation order.
template <StiffnessTarget kTarget>
void MeshSpringForceField::write_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  const double* records = std::get<SpringState>(state).records.data();
  parallel_chunks(
      springs_.size(), 1024,
      [&](std::size_t begin, std::size_t end) {
        fill_spring_pairs<kTarget>(records, springs_.data(), begin, end, -scale, k);
      },
      /*min_parallel=*/2048);
  // Setting the whole matrix, only the blocks above the diagonal were written: one pass over
  // the rows mirrors them below and sets each diagonal block to minus the rest of its row
  // (Σ K_s over the node's springs). Added to another field's values, both off-diagonal
  // blocks were written and the diagonal is gathered from the springs.
  parallel_chunks(
      diagonal_slots_.size(), 256,
      [&](std::size_t begin, std::size_t end) {
        if constexpr (kTarget == StiffnessTarget::kSetSingle) {
          k.complete_from_upper_single(begin, end);
        } else if constexpr (kTarget == StiffnessTarget::kSetDouble) {
          k.complete_from_upper(begin, end);
        } else {
          fill_spring_diagonal<kTarget>(records, incidence_.start.data(), incidence_.entries.data(),
                                        diagonal_slots_.data(), begin, end, scale, k);
        }
      },
      /*min_parallel=*/1024);
}

void MeshSpringForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  write_stiffness<StiffnessTarget::kAddDouble>(state, scale, k);
}

bool MeshSpringForceField::set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  if (!covers_pattern_) return false;
  write_stiffness<StiffnessTarget::kSetDouble>(state, scale, k);
  return true;
}

bool MeshSpringForceField::set_stiffness_single(const ForceFieldState& state, double scale,
                                                BlockSparseMatrix& k) const {
  if (!covers_pattern_) return false;
  write_stiffness<StiffnessTarget::kSetSingle>(state, scale, k);
  return true;
}

double MeshSpringForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState&) const {
  double energy = 0.0;
  for (const Spring& s : springs_) {
    const double stretch = (x.segment<3>(3 * static_cast<Eigen::Index>(s.nodes[1])) -
                            x.segment<3>(3 * static_cast<Eigen::Index>(s.nodes[0])))
                               .norm() -
                           s.rest_length;
    energy += 0.5 * s.stiffness * stretch * stretch;
  }
  return energy;
}

}  // namespace hof::mechanics
