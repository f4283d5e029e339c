#pragma once
/// @file
/// The interface every internal or applied force of a mechanical model implements. A force
/// field is built once (its element precomputation fixed), bound to the model's matrix pattern,
/// and then only read; what changes from step to step (element rotations, ...) lives in a
/// ForceFieldState owned by the MechanicalState.
///
/// Sign convention: `add_force` adds the force f(x, v) acting on the nodes; `add_stiffness`
/// adds scale·K with K = −∂f/∂x (positive semi-definite for a stable material), the matrix
/// the implicit and static solvers need.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "hof/core/types.h"
#include "hof/mechanics/block_sparse_matrix.h"

namespace hof::mechanics {

/// What a linear tetrahedral FEM field keeps per state (tetrahedron_fem_force_field.cpp).
struct TetrahedronFemState {
  /// Per element corner (padded to whole groups of simd lanes): the rotated, scaled shape
  /// gradient √V R b that the force pass writes and the stiffness reads.
  std::vector<double> scaled_gradients;
  /// Per element corner, same layout: its elastic force in the last pass, before the nodes
  /// gather them.
  std::vector<double> corner_forces;
};

/// What a hexahedral FEM field keeps per state: each element's rotation (co-rotational).
struct HexahedronFemState {
  std::vector<Mat3> rotations;  ///< (E)
};

/// What a spring field keeps per state: per spring (in simd groups) the record of its last
/// force evaluation that the stiffness reads (direction, length, stiffness terms).
struct SpringState {
  std::vector<double> records;
};

/// What a membrane (triangle FEM) field keeps per state.
struct MembraneState {
  std::vector<Mat3> frames;          ///< (T) each triangle's current in-plane frame (first two columns)
  std::vector<double> voigt_stress;  ///< (3T) each triangle's in-plane stress (xx, yy, xy), Pa·m
};

/// What a Neo-Hookean field keeps per state: each element's tangent dP/dF.
struct NeoHookeanState {
  std::vector<Eigen::Matrix<double, 9, 9>> tangents;  ///< (E)
};

/// Per-state data of a force field, made by ForceField::make_state(): one alternative per kind
/// of field (monostate: a field that keeps nothing, such as a constant force).
using ForceFieldState =
    std::variant<std::monostate, TetrahedronFemState, HexahedronFemState, SpringState, MembraneState, NeoHookeanState>;

class ForceField {
 public:
  ForceField() = default;
  ForceField(const ForceField&) = delete;
  ForceField& operator=(const ForceField&) = delete;
  virtual ~ForceField() = default;

  /// SOFA component type, e.g. "TetrahedronFEMForceField".
  [[nodiscard]] virtual std::string_view type_name() const = 0;
  /// The user's name for this instance (the scene's `name`), for messages.
  [[nodiscard]] const std::string& name() const { return name_; }
  void set_name(std::string name) { name_ = std::move(name); }

  /// State this field needs per MechanicalState.
  [[nodiscard]] virtual ForceFieldState make_state() const { return {}; }

  /// Node pairs this field couples in its stiffness (for the matrix pattern).
  virtual void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) const = 0;

  /// Precomputes the block slots this field writes. Called once while the model is built.
  virtual void bind(const BlockSparseMatrix& pattern) = 0;

  /// f += force at positions x and velocities v (3N each). Updates per-element data in `state`
  /// (rotations, tangents) that add_stiffness then uses.
  virtual void add_force(const Eigen::VectorXd& x, const Eigen::VectorXd& v, ForceFieldState& state,
                         Eigen::VectorXd& f) const = 0;

  /// K += scale · (−∂f/∂x), linearised at the positions of the last add_force.
  virtual void add_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const = 0;

  /// K = scale · (−∂f/∂x), overwriting every block of the matrix, for a field whose couplings
  /// cover the whole pattern: the caller then need not clear the matrix first. Returns false,
  /// writing nothing, when the field cannot (the caller clears and calls add_stiffness).
  virtual bool set_stiffness(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
    (void)state;
    (void)scale;
    (void)k;
    return false;
  }

  /// As set_stiffness, into the matrix's single-precision copy only (the double values are
  /// left stale): for the mixed-precision conjugate-gradient solve, half the memory written.
  virtual bool set_stiffness_single(const ForceFieldState& state, double scale, BlockSparseMatrix& k) const {
    (void)state;
    (void)scale;
    (void)k;
    return false;
  }

  /// Adds to `total` the sum of this field's forces on the nodes marked in `in_set` (one flag
  /// per node) at x and v, evaluating only the elements that touch them: a contact patch's
  /// reaction costs its few hundred elements instead of a pass over the whole body. The sum
  /// equals that of add_force's entries over the same nodes (to round-off). `scratch` is the
  /// caller's, its capacity reserved (no allocation while it suffices). Leaves the field's
  /// per-state data untouched. Returns false, adding nothing, when the field has no such path
  /// (the caller then evaluates the whole field).
  virtual bool add_force_sum_on(const Eigen::VectorXd& x, const Eigen::VectorXd& v, std::span<const std::int32_t> nodes,
                                std::span<const std::uint8_t> in_set, std::vector<std::int32_t>& scratch,
                                Vec3& total) const {
    (void)x;
    (void)v;
    (void)nodes;
    (void)in_set;
    (void)scratch;
    (void)total;
    return false;
  }

  /// Whether add_stiffness adds anything (constant forces do not).
  [[nodiscard]] virtual bool has_stiffness() const { return true; }

  /// Elastic (or potential) energy at x, J.
  [[nodiscard]] virtual double potential_energy(const Eigen::VectorXd& x, const ForceFieldState& state) const = 0;

  /// Index of an element this field cannot continue with at x (a linear element turned inside
  /// out), or −1. Checked after each step for divergence reports.
  [[nodiscard]] virtual std::int64_t find_invalid_element(const Eigen::VectorXd& x) const {
    (void)x;
    return -1;
  }

  /// What one element of this field is called in a sentence ("tetrahedron 12 is inverted").
  [[nodiscard]] virtual std::string_view element_noun() const { return "element"; }

 private:
  std::string name_;
};

}  // namespace hof::mechanics
