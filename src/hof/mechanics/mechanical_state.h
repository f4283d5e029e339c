#pragma once
/// @file
/// Everything about a mechanical model that changes while it runs: positions, velocities,
/// forces, the coupling input, per-field element data (a typed state per force field) and the
/// divergence report. The solver's scratch, factorisation and threads are its workspace
/// (detail/solver_workspace.h), held here only as an opaque handle.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hof/mechanics/fault.h"
#include "hof/mechanics/force_field.h"

namespace hof::mechanics {

struct MechanicalModel;

/// Why and where a model stopped. Once diverged, step() does nothing until reset().
struct Divergence {
  bool diverged{false};
  std::int64_t step{-1};  ///< step index at which it was detected
  Fault fault;            ///< what and where, as data
  // The fault in words (describe_fault), made once when step() reports it.
  std::string component;  ///< e.g. "TetrahedronFEMForceField 'FEM'" or "EulerExplicitSolver"
  std::string reason;     ///< one sentence
};

/// Timings and solver figures of the last step (for benchmarks and reports).
struct StepStats {
  double force_s{0.0};     ///< computing forces
  double assembly_s{0.0};  ///< filling the system matrix
  double solve_s{0.0};     ///< linear solves and updates
  int linear_iterations{0};
  double linear_residual{0.0};  ///< CG: |r|²/|b|² at exit; LDLT: 0
  int newton_iterations{0};
  double residual_force_n{0.0};  ///< static solver: |f| at exit
};

namespace detail {
/// The solver's workspace (detail/solver_workspace.h): scratch vectors sized once, the system
/// matrix, the direct solver's factorisation, the CG's coarse space and thread plan, and the
/// task arena the steps run in. Only the stepping code reads it.
struct SolverWorkspace;
}  // namespace detail

/// A stiffness block −∂f/∂x (N/m) that a force outside the model adds at one node for a step:
/// a contact spring lumped onto the nodes that carry the contact point (coupling/).
struct NodeStiffness {
  std::int32_t node{-1};
  Eigen::Matrix3d block{Eigen::Matrix3d::Zero()};
};

struct MechanicalState {
  MechanicalState();
  MechanicalState(MechanicalState&&) noexcept;
  MechanicalState& operator=(MechanicalState&&) noexcept;
  ~MechanicalState();

  Eigen::VectorXd x;               ///< (3N) positions, m
  Eigen::VectorXd v;               ///< (3N) velocities, m/s
  Eigen::VectorXd f;               ///< (3N) total force at the last evaluation, N
  Eigen::VectorXd external_force;  ///< (3N) N; written by the coupling before each step, kept
  /// The stiffness of the external force (its −∂f/∂x at single nodes; a node may appear more
  /// than once, the blocks add), written by the coupling with external_force and kept: the
  /// implicit integrator adds h (h + r_K)·block to the node's diagonal block of A, so that
  /// stiff contact springs stay stable at large steps. Empty (the default): A is exactly the
  /// model's. The caller reserves its capacity, so that filling it does not allocate. The
  /// other integrators read only external_force.
  std::vector<NodeStiffness> external_stiffness;
  double time_s{0.0};
  std::int64_t steps{0};
  std::vector<ForceFieldState> field_states;  ///< one per model force field
  Divergence divergence;
  StepStats stats;
  /// The solver's own (made by make_state): nothing physical, nothing a caller reads.
  std::unique_ptr<detail::SolverWorkspace> work;

  /// Node i's position / velocity.
  [[nodiscard]] Eigen::Vector3d position(std::int32_t i) const {
    return x.segment<3>(3 * static_cast<Eigen::Index>(i));
  }
  [[nodiscard]] Eigen::Vector3d velocity(std::int32_t i) const {
    return v.segment<3>(3 * static_cast<Eigen::Index>(i));
  }
};

/// A state at rest for `model`, with all scratch sized.
[[nodiscard]] MechanicalState make_state(const MechanicalModel& model);

/// Runs the state's steps on `threads` threads (0: the model's own setting, every core when
/// that is unset too). Results do not depend on it (the loops' chunks are fixed). Between
/// steps; it allocates.
void set_threads(const MechanicalModel& model, MechanicalState& state, int threads);

/// The threads the state's steps run on.
[[nodiscard]] int thread_count(const MechanicalState& state);

/// Sizes the scratch of point_elastic_force (forces.h) for patches touching up to `elements`
/// elements, so that a contact's reaction allocates nothing. Between steps; it allocates.
void reserve_point_force_scratch(const MechanicalModel& model, MechanicalState& state, std::size_t elements);

/// Back to rest: positions to rest, velocities and forces to zero, time to 0, divergence
/// cleared. Keeps the scratch (no allocation).
void reset(const MechanicalModel& model, MechanicalState& state);

}  // namespace hof::mechanics
