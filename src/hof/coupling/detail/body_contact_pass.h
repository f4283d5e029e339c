#pragma once
/// @file
/// Contact between bodies, the penalty response (SOFA's PenalityContactForceField): once per
/// world step, before the due bodies step, every body that takes part in contact offers its
/// current surface (and its sphere models) to collision::ContactDetector; each contact closer
/// than the contact distance becomes a spring along its normal,
///   f = k · (contact_distance − distance) · n,
/// +f on side a, −f on side b, each spread by the contact point's weights onto the surface
/// vertices and through the body's SurfaceMapping onto its nodes (state.external_force), and
/// the spring's stiffness k·n·nᵀ goes into the body's implicit solve
/// (MechanicalState::external_stiffness), so that stiff contact stays stable at dt 10–20 ms.
/// ContactResponse::kFrictionConstraint is solved the same way (the report says so) unless
/// ContactSettings::experimental_constraint_solver asks for the constraint response
/// (body_contact_constraints.h): then apply() only saves the start of the step and correct(),
/// after the due bodies have stepped, solves the contacts as constraints with Coulomb
/// friction. Either way contacts() lists the last pass's.

#include <cstdint>
#include <span>
#include <vector>

#include "hof/collision/body_contacts.h"
#include "hof/coupling/contact_settings.h"
#include "hof/coupling/detail/body_contact_constraints.h"
#include "hof/coupling/detail/body_contact_detection.h"
#include "hof/coupling/session.h"
#include "hof/coupling/surface_mapping.h"

namespace hof::coupling::detail {

struct World;
struct BodyRuntime;

/// The penalty stiffness of a pair of bodies, N/m: the settings' when neither body gives its
/// own, the one body's own when one does, and the geometric mean √(k_a·k_b) when both do.
/// SOFA multiplies the two models' contactStiffness (and divides by the contact distance:
/// BarycentricPenalityContact::setDetectionOutputs, stiffness = k1·k2 / (d0 + r1 + r2)); its
/// values are not N/m. HoF's are, and the geometric mean is the combination in N/m that is,
/// like SOFA's, multiplicative in each side's value, and gives a body pressed against one of
/// its own kind its own stiffness.
[[nodiscard]] double pair_contact_stiffness(const ContactSettings& settings, const BodyCollision& a,
                                            const BodyCollision& b);

/// Checks a session's contact settings and its bodies' collision models: a clear error naming
/// the body (or the setting) for a negative distance or stiffness, an alarm distance below the
/// contact distance, a collision model on a body with nothing to collide with, sphere models
/// whose centres and radii differ in number, or a deformable body whose spheres cannot be
/// mapped (no elements).
[[nodiscard]] Expected<void> validate_contacts(const ContactSettings& settings, std::span<const SessionBody> bodies);

class BodyContactPass {
 public:
  /// Sets the pass up for the world's bodies (their detector trees, the sphere centres'
  /// mappings, scratch sized): allocates. Nothing when config.contacts.enabled is false.
  void init(World& world);
  [[nodiscard]] bool active() const { return active_; }

  /// One pass: detection over every body taking part, then the penalty forces and stiffness
  /// onto the due deformable bodies (`due`: world body index → 1). Adds to their
  /// external_force (load_contacts cleared it) and rewrites their external_stiffness. Counts
  /// the contacts and the forces in `report` and the bodies' reports. No allocation once the
  /// contact list has grown to the most contacts any pass found.
  /// With the constraint response, only the bodies' start of step is saved (correct() then
  /// does the work).
  void apply(World& world, std::span<const char> due, SessionReport& report);

  /// After the due bodies stepped (their free motion), with the constraint response
  /// (kFrictionConstraint and experimental_constraint_solver): the constraint pass (BodyContactConstraints::apply)
  /// corrects their positions and velocities. Nothing with the penalty response.
  void correct(World& world, std::span<const char> due, SessionReport& report);

  /// The last pass's contacts within the contact distance (friction constraints: those that
  /// pushed, normal force > 0); body indices are the world's.
  [[nodiscard]] std::span<const collision::BodyContact> contacts() const { return active_contacts_; }
  /// Switches the contact of bodies `a` and `b` (world indices) off or on from the next pass
  /// (command::SetContactPair; the caller keeps ContactSettings::disabled_pairs). Nothing
  /// while the pass is inactive.
  void set_pair_enabled(std::size_t a, std::size_t b, bool enabled) {
    if (active_) detection_.set_pair_enabled(a, b, enabled);
  }

 private:
  // Whether the contacts are solved as constraints (body_contact_constraints.h).
  [[nodiscard]] bool constraints() const { return constraints_on_; }
  // Adds `force` (and the stiffness k·n·nᵀ, lumped) at one side's contact point.
  void add_side(World& world, const collision::ContactPoint& side, const Vec3& force, const Mat3& stiffness);

  bool active_{false};
  bool constraints_on_{false};
  BodyContactDetection detection_;
  BodyContactConstraints constraints_;  // kFrictionConstraint only
  std::vector<collision::BodyContact> active_contacts_;
  std::vector<Vec3> force_sum_;              // (bodies) this pass's contact force on each body
  std::vector<std::int64_t> contact_count_;  // (bodies) this pass's contacts of each body
  std::vector<char> due_;                    // (bodies) this pass's due bodies
  std::size_t stiffness_capacity_{0};        // entries reserved per body for external_stiffness
};

}  // namespace hof::coupling::detail
