#pragma once
/// @file
/// Contact between bodies, as the scene asks for it (typed: the strings of a SOFA collision
/// pipeline or a `.hof` `<contact>` element end in scene/). SessionConfig::contacts holds the
/// world's settings, SessionBody::collision each body's collision models.
///
/// Interface agreed before the implementation (issue 37).

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::coupling {

/// SOFA's contact responses (CollisionResponse `response`).
enum class ContactResponse : std::uint8_t {
  kPenalty,             ///< PenalityContactForceField: springs at the contact points, in the implicit solve
  kFrictionConstraint,  ///< FrictionContactConstraint: Coulomb friction, solved over the bodies' compliance
};

/// kFrictionConstraint: each node's compliance, the displacement a constraint force F acting
/// over one step makes there (body_contact_constraints.h; docs/mechanics.md says why the
/// default is the mass's).
enum class ConstraintCompliance : std::uint8_t {
  /// h²/m_i: the node as a free mass (SOFA's UncoupledConstraintCorrection with the ODE
  /// solver's integration factors). A correction then changes the body's momentum by exactly
  /// h·Σλ, along λ: the reported forces are the physical ones, and at rest they carry the
  /// body's weight.
  kLumpedMass,
  /// h²·A_ii⁻¹, A_ii the node's diagonal block of the implicit system (1 + h r_M) M +
  /// h (h + r_K) K (h²/m_i for explicit integrators). The node's own stiffness included, but
  /// the momentum a correction gives is m_i A_ii⁻¹ h λ, smaller than h λ and turned by the
  /// block's anisotropy: soft bodies gain sideways motion and the forces read too large.
  kSystemDiagonal,
};

/// The world's contact settings (SOFA: CollisionPipeline + intersection method + response).
struct ContactSettings {
  bool enabled{false};  ///< false: bodies pass through each other (only the tools touch them)
  ContactResponse response{ContactResponse::kPenalty};
  double alarm_distance_m{0.0};    ///< SOFA alarmDistance: closer pairs are detected, m (≥ contact distance)
  double contact_distance_m{0.0};  ///< SOFA contactDistance: the gap the response keeps, m
  double stiffness_n_per_m{0.0};   ///< penalty stiffness per contact (a body's own overrides), N/m
  double friction{0.0};            ///< Coulomb μ (SOFA responseParams "mu=…"), ≥ 0
  bool self_collision{false};      ///< default for bodies that do not say
  /// kFrictionConstraint: solve the contacts as constraints with Coulomb friction
  /// (coupling/detail/body_contact_constraints.h) instead of as penalty springs. Unfinished
  /// (issue 37; docs/mechanics.md gives what holds and what does not yet), so off: without it
  /// kFrictionConstraint is solved as penalty and the report says so.
  bool experimental_constraint_solver{false};
  /// kFrictionConstraint: the projected Gauss–Seidel's most sweeps per pass (SOFA
  /// GenericConstraintSolver maxIterations, LCPConstraintSolver maxIt; SOFA's default 1000).
  int constraint_max_iterations{1000};
  /// kFrictionConstraint: the sweeps stop when none changed a contact's violation (its gap
  /// and tangential slip after the correction) by more than this, m. SOFA's `tolerance` is in
  /// its own units (a sum over the constraints), so HoF keeps its own in metres.
  double constraint_tolerance_m{1e-9};
  ConstraintCompliance constraint_compliance{ConstraintCompliance::kLumpedMass};
  /// kFrictionConstraint: solves per world step. After each but the last, the bodies that
  /// were pushed step again from the start of the step with the contact forces in their load
  /// (their whole volume answers within the step); the last one's correction is projected
  /// onto the contact nodes. 1: the plain free-motion scheme (a soft body's contact nodes are
  /// corrected alone, and the rest of it hears of the contact a step late).
  int constraint_force_passes{3};
  /// Pairs of bodies (indices into the session's bodies, smaller first) switched off.
  std::vector<std::pair<std::int32_t, std::int32_t>> disabled_pairs;
};

/// One body's collision models (a SOFA node's Triangle/Line/Point/SphereCollisionModel).
struct BodyCollision {
  bool enabled{false};  ///< the body takes part in contact between bodies
  bool triangles{true};
  bool lines{true};
  bool points{true};
  /// SphereCollisionModel: centres at rest (world frame, m) and radii (m). The coupling maps
  /// the centres through the body's volume (barycentric, as SOFA's `BarycentricMapping`).
  std::vector<Vec3> sphere_centers;
  std::vector<double> sphere_radii;
  bool moving{true};
  bool simulated{true};
  std::int32_t group{-1};                   ///< SOFA `group`; −1: none
  std::optional<bool> self_collision;       ///< unset: ContactSettings::self_collision
  std::optional<double> stiffness_n_per_m;  ///< SOFA `contactStiffness` on the model
};

}  // namespace hof::coupling
