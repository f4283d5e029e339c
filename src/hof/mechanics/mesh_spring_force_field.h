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
#include "hof/mechanics/node_incidence.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/stiffness_writer.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

/// How a spring's own stiffness and damping follow from the configured values.
enum class SpringStiffnessRule {
  /// Every spring gets the configured values: k in N/m, c in N·s/m (the thesis' surface
  /// springs, an X3D DeformableShape).
  kSameForEverySpring,
  /// SOFA's MeshSpringForceField: the configured values are per unit strain, each spring gets
  /// k/l0 (N/m) and c/l0 (N·s/m) with l0 its rest length — a short edge is stiffer, as a short
  /// bar of the same section is (MeshSpringForceField::addSpring, which passes `stiffness / l`
  /// and `damping / l` to the spring it adds).
  kDividedByRestLength,
};

/// The stiffness matrix a spring adds to the implicit system (its force is the same either way).
/// With f the spring's tension, l its length and u its direction, −∂f_i/∂x_i =
/// k u uᵀ + (f/l)(I − u uᵀ): the transverse term f/l is negative for a compressed spring.
enum class SpringTangent {
  /// The transverse term without the damper's tension, clamped at zero (Choi & Ko, "Stable but
  /// responsive cloth", SIGGRAPH 2002): the matrix stays positive semi-definite for CG.
  kClampedTransverse,
  /// SOFA's (SpringForceField::computeSpringForce, StiffSpringForceField): (k − f/l) u uᵀ +
  /// (f/l) I with f including the damper's tension, never clamped. An implicit step with it
  /// is SOFA's step; a strongly compressed mesh can make the system indefinite.
  kExact,
};

/// Stiffness and damping of the springs of one element kind (SOFA's `trianglesStiffness`
/// `trianglesDamping`, `tetrahedraStiffness` `tetrahedraDamping`). Units as MeshSpringConfig's.
struct SpringValues {
  double stiffness{0.0};
  double damping{0.0};
};

struct MeshSpringConfig {
  /// SOFA `stiffness` (all element kinds). N/m per spring (kSameForEverySpring) or N per unit
  /// strain (kDividedByRestLength).
  double stiffness_n_per_m{0.0};
  double damping_n_s_per_m{0.0};  ///< SOFA `damping`; N·s/m, or N·s per unit strain rate
  /// Rest length of each spring as a fraction of its length in the given shape: below 1 the
  /// springs start in tension (a drum skin, whose tension gives a flat sheet the stiffness
  /// across its plane that untensioned springs lack). 1 = SOFA's behaviour.
  double rest_length_scale{1.0};
  /// kSameForEverySpring keeps HoF's own models as they were; a SOFA scene's springs are
  /// kDividedByRestLength.
  SpringStiffnessRule rule{SpringStiffnessRule::kSameForEverySpring};
  /// kClampedTransverse keeps HoF's own models as they were; a SOFA scene's springs are kExact.
  SpringTangent tangent{SpringTangent::kClampedTransverse};
  /// Per element kind, replacing (stiffness, damping) for the edges of that kind. As SOFA's
  /// MeshSpringForceField::init, the kinds are taken in the order triangles, tetrahedra; an
  /// edge shared by both gets one spring, with the values of the first kind that has it; a
  /// kind whose stiffness and damping are both 0 adds no springs (its edges take the next
  /// kind's values).
  std::optional<SpringValues> triangles{};
  std::optional<SpringValues> tetrahedra{};
};

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
  NodeIncidence incidence_;  // spring·2 + end
  std::vector<std::int32_t> diagonal_slots_;
  bool covers_pattern_{false};  // the pattern is the springs' node pairs and the diagonal
};

}  // namespace hof::mechanics
