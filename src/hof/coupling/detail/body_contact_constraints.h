#pragma once
/// @file
/// Contact between bodies, the constraint response with Coulomb friction (SOFA's
/// FrictionContactConstraint solved by GenericConstraintSolver or LCPConstraintSolver under a
/// FreeMotionAnimationLoop; Duriez, Dubois, Kheddar & Andriot 2006, "Realistic haptic
/// rendering of interacting deformable objects in virtual environments", IEEE TVCG 12(1)).
///
/// The free-motion scheme, once per world step, after the due bodies have stepped without
/// contact (their free motion):
///  1. detection on the free positions: every contact within the alarm distance is one row
///     triple (normal n from b toward a, tangents t₁, t₂) acting on the points of its two
///     sides, which the surface weights and each body's SurfaceMapping spread onto nodes
///     (the rows of H);
///  2. each body's compliance C (m/N): per node the 3x3 block h²·A_ii⁻¹, A_ii the node's
///     diagonal block of the implicit system (1 + h r_M) M + h (h + r_K) K that its step just
///     solved — SOFA's UncoupledConstraintCorrection (a diagonal compliance) generalised from
///     a given per-node value to the block the integrator already has; h²/m_i for the other
///     integrators (explicit Euler: exactly the displacement a force makes in one step).
///     Rigid bodies, held dofs, bodies that do not react (SOFA simulated="0") and bodies that
///     do not step this world step: zero;
///  3. the Delassus operator W = Σ_bodies H C Hᵀ, its 3x3 block per contact kept, the
///     coupling between contacts applied through the nodes' displacements (never formed);
///  4. projected Gauss–Seidel over the contacts (Duriez et al. 2006 §4; SOFA's
///     GenericConstraintSolver): per contact the 3x3 local problem with the others' forces
///     fixed, the normal force λn ≥ 0 with the gap after correction ≥ the contact distance
///     (Signorini), the tangential force in the disk |λt| ≤ μ λn (Coulomb: stick keeps the
///     points' relative tangential velocity at zero, slip puts λt on the disk's rim), sweeps
///     in contact order until none changes a violation by more than the tolerance or the
///     sweeps run out;
///  5. the correction Δx = C Hᵀ λ onto the due bodies' positions and Δx/h onto their
///     velocities.
/// λ is a force, N: the constant force over the step that makes the correction (with the
/// compliance h²·A⁻¹, the implicit step's response to a force F is Δx = h² A⁻¹ F). The report
/// carries it as the penalty pass's does (+Hᵀλ on side a, −Hᵀλ on side b).
///
/// Deterministic (contacts in the detector's order, sweeps in that order); no allocation once
/// the contact list has grown to the most contacts any pass found.

#include <cstdint>
#include <span>
#include <vector>

#include "hof/collision/body_contacts.h"
#include "hof/coupling/contact_settings.h"
#include "hof/coupling/session.h"

namespace hof::coupling::detail {

struct World;
class BodyContactDetection;

class BodyContactConstraints {
 public:
  /// Sizes the per-node scratch of the world's bodies: allocates.
  void init(World& world);

  /// Before the due bodies step: their state and load at the start of the step (a body
  /// pushed by its contacts steps again from there). No allocation.
  void save_start(World& world, std::span<const char> due);

  /// One pass on the free motion just taken by the due bodies (`due`: world body index → 1):
  /// detection, the solve, the correction. Fills `pushing` with the contacts whose normal
  /// force is > 0 and counts them and their forces in `report` and the bodies' reports.
  void apply(World& world, BodyContactDetection& detection, std::span<const char> due, SessionReport& report,
             std::vector<collision::BodyContact>& pushing);

  /// The last pass's sweeps (for tests and reports) and its largest violation change at exit, m.
  [[nodiscard]] int last_sweeps() const { return last_sweeps_; }
  [[nodiscard]] double last_change_m() const { return last_change_m_; }

 private:
  // One node a contact acts on, with its signed weight (+ side a, − side b).
  struct Entry {
    std::int32_t body{-1};
    std::int32_t node{-1};
    double weight{0.0};
    bool correctable{false};  // the body reacts this step (its compliance is not zero)
  };
  // One contact's row triple.
  struct Row {
    Mat3 frame;     // rows n, t1, t2
    Mat3 delassus;  // W's 3x3 block of this contact, local frame, m/N
    Mat3 delassus_inverse;
    double gap{0.0};  // free-motion gap less the contact distance, m
    Vec3 free;        // its violation in the free motion: gap − contact distance, h·(relative tangential velocity)
    Vec3 lambda;      // its force, local frame, N
    std::uint32_t first{0}, count{0};  // its entries
    double mu{0.0};
  };
  struct BodyScratch {
    Eigen::VectorXd x0, v0, f0;  // (3N) the state at the start of the step, and its load
    std::int64_t steps0{0};
    double time0{0.0};
    Eigen::VectorXd x_free;           // (3N) the positions of the free motion
    Eigen::VectorXd extra;            // (3N) the contact forces on the nodes, N
    std::vector<Mat3> compliance;     // (N) h²·A_ii⁻¹ (or h²/m), held dofs zero; valid where stamp == pass
    std::vector<Vec3> displacement;   // (N) this pass's correction Δx
    std::vector<std::int64_t> stamp;  // (N) the pass that last touched the node
  };

  // Detection on the current (free) positions; the rows, their compliances and Delassus blocks.
  void build_rows(World& world, BodyContactDetection& detection);
  // Projected Gauss–Seidel from the rows' current forces; displacement = C Hᵀ (λ − λ before).
  void sweep(const ContactSettings& settings);
  // The node's compliance and zero displacement, once per pass (the first time a row touches it).
  void touch(World& world, std::size_t body, std::int32_t node);

  std::vector<BodyScratch> bodies_;
  std::vector<char> due_;
  std::vector<collision::BodyContact> detected_;
  std::vector<Row> rows_;
  std::vector<Entry> entries_;
  std::vector<Entry> touched_;  // the nodes this pass touched, each once
  std::vector<Vec3> force_sum_;
  std::vector<std::int64_t> contact_count_;
  std::int64_t pass_{0};
  int last_sweeps_{0};
  double last_change_m_{0.0};
};

}  // namespace hof::coupling::detail
