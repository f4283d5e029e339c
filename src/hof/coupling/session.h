#pragma once
/// @file
/// A haptic session on one deformable body: the thesis' `Motion` node, improved. Three loops —
/// haptic (≥ 1 kHz), simulation (fixed dt) and graphics — exchange snapshots: the haptic loop
/// renders against the latest surface snapshot and publishes contacts; each simulation step
/// turns the contacts of the ticks since the last step into forces on the tissue, steps the
/// mechanics, maps the volume to the surface and publishes a new snapshot.
///
/// Contact → tissue (reaction = −force sent to the device, averaged over the step's ticks):
///  - `kClosestVertex`: all of it on the contact triangle's vertex nearest the contact (the
///    thesis);
///  - `kBarycentric`: spread over the contact triangle's three vertices by the contact
///    point's barycentric weights.
/// In virtual time the loops run in lock-step on the calling thread (N haptic ticks per
/// simulation step): runs are deterministic.

#include <functional>
#include <memory>
#include <string>

#include "hof/core/error.h"
#include "hof/core/progress.h"
#include "hof/coupling/surface_mapping.h"
#include "hof/haptics/device.h"
#include "hof/haptics/haptic_loop.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::coupling {

enum class ContactCoupling : std::uint8_t {
  kClosestVertex,  ///< the thesis: the force on the contact triangle's nearest vertex
  kBarycentric,    ///< spread over the contact triangle by the contact point's weights
  /// barycentric forces, and with every step the contact point's 3x3 compliance from the
  /// FEM state goes to the haptic loop, which renders the tissue's own reaction at 1 kHz
  kCompliance,
};

struct SessionConfig {
  haptics::HapticLoopConfig haptics;  ///< rate, renderer, surface, safety, calibration
  ContactCoupling coupling{ContactCoupling::kBarycentric};
  haptics::ForceEffects effects;      ///< H3D force effects added to the contact force
  collision::AabbTreeOptions tree;    ///< the surface's bound tree (H3D useBoundTree, maxTrianglesInLeaf)
};

/// The body: its mechanics and the touchable surface that follows it.
struct SessionBody {
  std::string name;
  mechanics::MechanicalModel model;
  mesh::TriMesh surface;    ///< rest shape of the touchable surface
  SurfaceMapping mapping;   ///< volume → surface
};

/// What a run measured.
struct SessionReport {
  double simulated_s{0.0};
  std::int64_t haptic_ticks{0};
  std::int64_t simulation_steps{0};
  double wall_s{0.0};
  double simulation_steps_per_s{0.0};        ///< achieved (wall clock)
  /// Simulation steps per second of wall time in the thesis' three states (the rate a
  /// graphics loop showing each new shape could reach): untouched and at rest, deforming
  /// without contact, in contact.
  double rate_untouched{0.0}, rate_deforming{0.0}, rate_in_contact{0.0};
  double max_force_n{0.0};
  double contact_time_s{0.0};
  std::int64_t fall_through_events{0};      ///< simulation steps whose proxy was inside the (closed) surface
  bool diverged{false};
  std::string divergence;
  double max_displacement_m{0.0};
  haptics::PeriodStats haptic_periods;
  haptics::SafetyCounters safety;
};

class Session {
 public:
  static Expected<std::unique_ptr<Session>> make(SessionBody body, std::unique_ptr<haptics::Device> device,
                                                 const SessionConfig& config);

  /// Runs `seconds` of virtual time in lock-step. `on_sample` receives every haptic tick's
  /// sample (for telemetry); `progress` is told how far along the run is.
  SessionReport run_virtual(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                            const ProgressSink& progress = {});

  /// Runs `seconds` of wall time: haptic loop on its own thread, simulation on another,
  /// telemetry drained here. Reports achieved rates.
  SessionReport run_realtime(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                             const ProgressSink& progress = {});

  [[nodiscard]] const mechanics::MechanicalModel& model() const { return body_.model; }
  [[nodiscard]] const mechanics::MechanicalState& state() const { return state_; }
  [[nodiscard]] const SessionBody& body() const { return body_; }

 private:
  Session(SessionBody body, std::unique_ptr<haptics::Device> device, const SessionConfig& config);
  struct StateTimer;  // wall time per state (untouched, deforming, in contact)
  // Rates, periods, safety counters and displacement, common to both run modes.
  void finish_report(SessionReport& report, const StateTimer& timer, double wall_s) const;
  // Turns the accumulated contact of the last ticks into external forces on the tissue.
  void apply_contact_forces();
  // Maps the volume to the surface and publishes a snapshot.
  void publish_surface(double time_s);
  bool proxy_inside(const Vec3& p) const;
  void accumulate(const haptics::HapticSample& s);

  SessionBody body_;
  std::unique_ptr<haptics::Device> device_;
  SessionConfig config_;
  mechanics::MechanicalState state_;
  TripleBuffer<haptics::SurfaceSnapshot> surfaces_;
  std::unique_ptr<haptics::HapticLoop> loop_;
  std::vector<Vec3> surface_positions_, surface_velocities_;
  // Contact accumulated since the last simulation step.
  Vec3 reaction_sum_{Vec3::Zero()};
  int contact_ticks_{0};
  int contact_ticks_since_publish_{0};
  int ticks_since_step_{0};
  std::int32_t last_triangle_{-1};
  Vec3 last_reaction_{Vec3::Zero()};  // force applied on the tissue in the last step
  Vec3 last_barycentric_{Vec3::Zero()};
  Vec3 last_proxy_{Vec3::Zero()};
  bool last_proxy_valid_{false};
  bool surface_closed_{false};  // fall-through is counted only for closed surfaces
};

}  // namespace hof::coupling
