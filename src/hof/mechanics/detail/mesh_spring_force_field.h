#pragma once
/// @file
/// Springs on the unique edges of a mesh, as SOFA's MeshSpringForceField — the model the
/// thesis recommends for its speed. Each spring: f = (k (l − l0) + c (v_j − v_i)·u) u along
/// the unit edge direction u, rest length l0 = the edge length at rest.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/detail/node_incidence.h"
#include "hof/mechanics/detail/stiffness_writer.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/force_field_config.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

class MeshSpringForceField final : public ForceField {
 public:
  /// One spring per unique edge of `triangles` and `tets` (see MeshSpringConfig for which
  /// values an edge gets). Errors: a negative or non-finite stiffness or damping, a rest length
  /// scale outside (0, 2], no edges, an edge to a missing node, a zero-length edge.
  static Expected<std::unique_ptr<MeshSpringForceField>> make(const std::vector<Vec3>& rest_positions,
                                                              const std::vector<mesh::Tet>& tets,
                                                              const std::vector<mesh::Tri>& triangles,
                                                              const MeshSpringConfig& config, std::string name);

  [[nodiscard]] std::string_view type_name() const override { return "MeshSpringForceField"; }
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const override;
  void bind(const BlockSparseMatrix& pattern) override;
  bool add_force_sum_on(const Eigen::VectorXd& x, const Eigen::VectorXd& v, std::span<const std::int32_t> nodes,
                        std::span<const std::uint8_t> in_set, std::vector<std::int32_t>& scratch,
                        Vec3& total) const override;
  void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                 Eigen::VectorXd& f) const override;
  void add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  bool set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  bool set_stiffness_single(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const override;
  [[nodiscard]] double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const override;
  [[nodiscard]] ForceFieldState make_state() const override;

  [[nodiscard]] std::size_t spring_count() const { return springs_.size(); }
  /// The nodes, rest length (m), stiffness (N/m) and damping (N·s/m) of spring s, in the
  /// order of the sorted node pairs.
  struct SpringView {
    std::array<std::int32_t, 2> nodes;
    double rest_length_m;
    double stiffness_n_per_m;
    double damping_n_s_per_m;
  };
  [[nodiscard]] SpringView spring(std::size_t s) const {
    const Spring& x = springs_[s];
    return {x.nodes, x.rest_length, x.stiffness, x.damping};
  }

 private:
  struct Spring {
    std::array<std::int32_t, 2> nodes;
    double rest_length;
    double stiffness;                   // this spring's k, N/m
    double damping;                     // this spring's c, N·s/m
    std::array<std::int32_t, 2> slots;  // (i,j) (j,i) with i < j
  };
  // Four springs side by side for the spring pass (one SIMD lane each); padded with copies
  // of spring 0 whose results are never read.
  struct SpringGroup {
    std::int32_t first[4];
    std::int32_t second[4];
    double rest_length[4];
    double stiffness[4];
    double damping[4];
  };
  MeshSpringForceField() = default;
  // Groups [begin, end) of the spring pass (plain pointers keep the loop in registers).
  static void spring_groups(const SpringGroup* groups, std::size_t begin, std::size_t end, const double* xs,
                            const double* vs, bool exact_tangent, double* records);
  template <StiffnessTarget kTarget>
  void write_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const;

  std::vector<Spring> springs_;
  std::vector<SpringGroup> groups_;
  bool exact_tangent_{false};  // SpringTangent::kExact
  NodeIncidence incidence_;    // spring·2 + end
  std::vector<std::int32_t> diagonal_slots_;
  bool covers_pattern_{false};  // the pattern is the springs' node pairs and the diagonal
};

}  // namespace hof::mechanics
