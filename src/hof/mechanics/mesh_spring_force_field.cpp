#include "hof/mechanics/mesh_spring_force_field.h"

#include <fmt/format.h>

#include <cmath>

#include "hof/mechanics/parallel.h"

#include "hof/mesh/boundary.h"

namespace hof::mechanics {

Expected<std::unique_ptr<MeshSpringForceField>> MeshSpringForceField::make(
    const std::vector<Vec3>& rest_positions, const std::vector<mesh::Tet>& tets,
    const std::vector<mesh::Tri>& triangles, const MeshSpringConfig& config, std::string name) {
  const std::string who = fmt::format("MeshSpringForceField '{}'", name);
  if (!(config.stiffness_n_per_m >= 0.0) || !std::isfinite(config.stiffness_n_per_m)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: stiffness must be >= 0 N/m, got {}", who, config.stiffness_n_per_m));
  }
  if (!(config.damping_n_s_per_m >= 0.0) || !std::isfinite(config.damping_n_s_per_m)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: damping must be >= 0 N·s/m, got {}", who, config.damping_n_s_per_m));
  }
  std::vector<mesh::Edge> edges = mesh::tet_edges(tets);
  const std::vector<mesh::Edge> surface_edges = mesh::triangle_edges(triangles);
  edges.insert(edges.end(), surface_edges.begin(), surface_edges.end());
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  if (edges.empty()) return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: the topology has no edges", who));

  auto field = std::unique_ptr<MeshSpringForceField>(new MeshSpringForceField());
  field->set_name(std::move(name));
  field->config_ = config;
  field->springs_.reserve(edges.size());
  for (const mesh::Edge& e : edges) {
    if (e[0] < 0 || static_cast<std::size_t>(e[1]) >= rest_positions.size()) {
      return make_error(ErrorCode::kInvalidMesh, fmt::format("{}: edge {}-{} refers to a missing node", who, e[0], e[1]));
    }
    const double length = (rest_positions[e[1]] - rest_positions[e[0]]).norm();
    if (!(length > 0.0)) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("{}: nodes {} and {} coincide at rest (zero-length spring)", who, e[0], e[1]));
    }
    field->springs_.push_back({{e[0], e[1]}, length, {-1, -1, -1, -1}});
  }
  std::vector<std::array<std::int32_t, 2>> node_lists;
  node_lists.reserve(field->springs_.size());
  for (const Spring& s : field->springs_) node_lists.push_back(s.nodes);
  field->incidence_ = make_node_incidence<2>(node_lists, rest_positions.size());
  return field;
}

ForceFieldState MeshSpringForceField::make_state() const {
  // element_matrices[s]: the spring's stiffness block −∂f_i/∂x_i at the last positions;
  // element_scalars[3s..3s+2]: the force on its first node.
  ForceFieldState s;
  s.element_matrices.assign(springs_.size(), Mat3::Zero());
  s.element_scalars.assign(3 * springs_.size(), 0.0);
  return s;
}

void MeshSpringForceField::collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const {
  for (const Spring& s : springs_) pairs.emplace_back(s.nodes[0], s.nodes[1]);
}

void MeshSpringForceField::bind(const BlockSparseMatrix& pattern) {
  for (Spring& s : springs_) {
    const auto [i, j] = s.nodes;
    s.slots = {static_cast<std::int32_t>(pattern.slot(i, i)), static_cast<std::int32_t>(pattern.slot(i, j)),
               static_cast<std::int32_t>(pattern.slot(j, i)), static_cast<std::int32_t>(pattern.slot(j, j))};
  }
}

void MeshSpringForceField::add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                                     Eigen::VectorXd& f) const {
  const double k = config_.stiffness_n_per_m;
  const double c = config_.damping_n_s_per_m;
  // Spring pass: tension and stiffness block of each spring, independently.
  parallel_chunks(
      springs_.size(), 256,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t index = begin; index < end; ++index) {
          const Spring& s = springs_[index];
          const Eigen::Index i = 3 * static_cast<Eigen::Index>(s.nodes[0]);
          const Eigen::Index j = 3 * static_cast<Eigen::Index>(s.nodes[1]);
          const Vec3 d = x.segment<3>(j) - x.segment<3>(i);
          const double length = d.norm();
          Eigen::Map<Vec3> force_on_first(state.element_scalars.data() + 3 * index);
          if (!(length > 0.0)) {
            force_on_first.setZero();
            state.element_matrices[index] = k * Mat3::Identity();
            continue;
          }
          const Vec3 u = d / length;
          const double tension = k * (length - s.rest_length) + c * (v.segment<3>(j) - v.segment<3>(i)).dot(u);
          force_on_first = tension * u;
          // −∂f_i/∂x_i = k u uᵀ + k (1 − l0/l)(I − u uᵀ). The transverse term is negative for
          // a compressed spring; it is clamped at zero so that the system matrix stays
          // positive definite (Choi & Ko, "Stable but responsive cloth", SIGGRAPH 2002).
          const Mat3 uu = u * u.transpose();
          const double transverse = std::max(0.0, k * (1.0 - s.rest_length / length));
          state.element_matrices[index] = (k - transverse) * uu + transverse * Mat3::Identity();
        }
      },
      /*min_parallel=*/1024);
  // Node pass: each node gathers its springs' forces in a fixed order.
  parallel_chunks(
      incidence_.start.size() - 1, 256,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t n = begin; n < end; ++n) {
          Vec3 sum = Vec3::Zero();
          for (std::int32_t entry : incidence_.of(n)) {
            const Eigen::Map<const Vec3> force_on_first(state.element_scalars.data() + 3 * (entry >> 1));
            if (entry & 1) sum -= force_on_first;
            else sum += force_on_first;
          }
          f.segment<3>(3 * static_cast<Eigen::Index>(n)) += sum;
        }
      },
      /*min_parallel=*/1024);
}

void MeshSpringForceField::add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
  // Row pass: node n adds +K_s to its diagonal block and −K_s to the block of the other end.
  parallel_chunks(
      incidence_.start.size() - 1, 256,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t n = begin; n < end; ++n) {
          for (std::int32_t entry : incidence_.of(n)) {
            const Spring& s = springs_[static_cast<std::size_t>(entry >> 1)];
            const Mat3 block = scale * state.element_matrices[static_cast<std::size_t>(entry >> 1)];
            const bool second = (entry & 1) != 0;
            k.block(second ? s.slots[3] : s.slots[0]) += block;
            k.block(second ? s.slots[2] : s.slots[1]) -= block;
          }
        }
      },
      /*min_parallel=*/1024);
}

double MeshSpringForceField::potential_energy(const Eigen::VectorXd& x, const ForceFieldState&) const {
  double energy = 0.0;
  for (const Spring& s : springs_) {
    const double stretch =
        (x.segment<3>(3 * static_cast<Eigen::Index>(s.nodes[1])) - x.segment<3>(3 * static_cast<Eigen::Index>(s.nodes[0])))
            .norm() - s.rest_length;
    energy += 0.5 * config_.stiffness_n_per_m * stretch * stretch;
  }
  return energy;
}

}  // namespace hof::mechanics
