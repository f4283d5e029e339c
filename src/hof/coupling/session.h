#pragma once
/// @file
/// A haptic session on a world of bodies: the thesis' `Motion` node, grown to several bodies.
/// Three loops exchange snapshots and never wait on each other:
///  - the haptic loop (≥ 1 kHz, own thread) renders one proxy against every touchable surface
///    of the world at once (one snapshot, one bound tree, each body a part with its own
///    triangle range and material) and sends each tick's contact on its own channel;
///  - the simulation (fixed dt, own thread in real time) runs step_world(): commands → the
///    contacts since the last step become forces on the touched body only → every deformable
///    body steps (in parallel when there are several) → one snapshot is published;
///  - the supervisor (the `hof run` command, later the window or a script) reads telemetry
///    and snapshots, and changes settings only through submit() (the command seam).
/// In virtual time the loops run in lock-step on the calling thread (N haptic ticks per
/// simulation step) through the same step_world(): runs are deterministic.
///
/// Contact → tissue (reaction = −force sent to the device, averaged over the step's ticks):
///  - `kClosestVertex`: all of it on the contact triangle's vertex nearest the contact (the
///    thesis);
///  - `kBarycentric`: spread over the contact triangle's three vertices by the contact
///    point's barycentric weights;
///  - `kCompliance`, `kFemReaction`: barycentric, and the felt force comes from the FEM (see
///    ContactCoupling).
/// Bodies collide with each other when config.contacts asks for it (penalty springs:
/// coupling/detail/body_contact_pass.h); otherwise each feels only the proxy.
///
/// Hands (issue 37, two devices at once): the device given to make() is the first hand; each
/// SessionConfig::more_hands entry, with its own device, is one more, with its own haptic loop
/// (renderer and proxy, safety filter and force limit, calibration) and its own tool. Every
/// hand renders the same surfaces (a snapshot buffer per hand: a TripleBuffer has one reader),
/// its contacts become forces on the bodies it touched, and it feels only its own tool's force.
/// The first hand is the session's as it was before: telemetry, fall-through, the compliance
/// and FEM-reaction local models, the commands (calibration, force limit, device switch).

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "hof/core/cpu_affinity.h"
#include "hof/core/error.h"
#include "hof/core/progress.h"
#include "hof/core/triple_buffer.h"
#include "hof/coupling/command_seam.h"
#include "hof/coupling/contact_settings.h"
#include "hof/coupling/contact_view.h"
#include "hof/coupling/surface_mapping.h"
#include "hof/coupling/tool_coupling.h"
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
  /// The haptic rate (issue 17): the simulation steps once per haptic tick (each deformable
  /// body's dt must equal the haptic period), the tissue takes each tick's contact force as
  /// `kBarycentric` does, and what the hand feels at the next tick is the FEM's own reaction
  /// of that step: the tissue's elastic force summed over the nodes within 1 cm of the contact
  /// point (held nodes left out), not a rendering spring, evaluated from the elements that
  /// touch those nodes (mechanics::point_elastic_force). The felt stiffness is then the
  /// tissue's (E, ν, the organ's shape), whatever the surface material's stiffness, which only
  /// sets how firmly the tool drags the contact point.
  kFemReaction,
};

/// One more hand beyond the first (its device is given to Session::make beside the first's).
struct HandConfig {
  std::string device;  ///< the device spec it was opened from (reported)
  /// Its loop: its own safety (force limit), calibration and renderer; the rate must be the
  /// first hand's (virtual time ticks every hand in lock-step).
  haptics::HapticLoopConfig haptics;
  std::shared_ptr<haptics::Tool> tool;  ///< its tool (null: a point/sphere stylus)
  std::shared_ptr<ToolTissueCoupling> tool_coupling;
};

struct SessionConfig {
  haptics::HapticLoopConfig haptics;  ///< rate, renderer, surface, safety, calibration
  ContactCoupling coupling{ContactCoupling::kBarycentric};
  haptics::ForceEffects effects;    ///< H3D force effects added to the contact force
  collision::AabbTreeOptions tree;  ///< the surfaces' bound tree (H3D useBoundTree, maxTrianglesInLeaf)
  /// A tool on the stylus (a needle: procedures/needle.h), ticked by the haptic loop, and the
  /// per-step hook that gives its reaction to the tissue. Null: the stylus is a point/sphere.
  std::shared_ptr<haptics::Tool> tool;
  std::shared_ptr<ToolTissueCoupling> tool_coupling;
  /// Contact between bodies (off unless the scene asks for it).
  ContactSettings contacts{};
  /// The first hand's device spec (reported beside the others'; may be empty).
  std::string device;
  /// The hands beyond the first (empty: one device, as before).
  std::vector<HandConfig> more_hands;
  /// Threads of the simulation in real time (0: automatic, every core but one, which the
  /// haptic loop and the window share). Virtual-time runs step on the caller's thread.
  int simulation_threads{0};
  /// Real time: the haptic loop and the snapshot publisher on the last CPU the process may
  /// use, the simulation on the others (with two or more; core/cpu_affinity.h says why).
  bool pin_threads{true};
};

/// A body of the world: deformable (a model, and the touchable surface that follows it
/// through `mapping`) or rigid and fixed (no model: the surface never moves).
struct SessionBody {
  std::string name;
  std::optional<mechanics::MechanicalModel> model;  ///< set for deformable bodies
  mesh::TriMesh surface;                            ///< rest shape of the touchable surface (world frame)
  SurfaceMapping mapping;                           ///< volume → surface (deformable bodies)
  /// Its haptic surface; unset: the session's material (config.haptics.material).
  std::optional<haptics::SurfaceMaterial> material;
  /// What the model was built from: commands that change a parameter rebuild from it.
  std::optional<mechanics::ModelConfig> config;
  /// Haptic layer (H3D HapticLayeredGroup): bodies of each layer are felt through a proxy of
  /// their own, and the layers' forces add up. Layers are taken in increasing order.
  int layer{0};
  /// Its collision models for contact between bodies (enabled only when the scene gives some).
  BodyCollision collision{};

  [[nodiscard]] bool deformable() const { return model.has_value(); }
};

/// What a run measured for one body.
struct BodyReport {
  std::string name;
  bool deformable{false};
  std::size_t nodes{0};
  double max_displacement_m{0.0};
  double contact_time_s{0.0};
  double max_force_n{0.0};
  std::int64_t fall_through_events{0};
  bool probe_started_inside{false};  ///< the proxy was inside this body at its first reading
  // Contact between bodies (SessionConfig::contacts), as the last pass left it and its largest.
  std::int64_t body_contacts{0};            ///< contacts of this body with others (or itself)
  std::int64_t max_body_contacts{0};        ///< the most at any pass of the run
  Vec3 body_contact_force_n{Vec3::Zero()};  ///< total contact force on this body, N
  double max_body_contact_force_n{0.0};     ///< the largest |total| at any pass, N
};

/// What a run measured for one hand (device, loop and tool).
struct HandReport {
  std::string device;                     ///< its device spec, or the device's name when none was given
  double max_force_n{0.0};                ///< the largest force sent to its device
  double contact_time_s{0.0};             ///< ticks in contact with a body
  std::int64_t clamped_contact_ticks{0};  ///< contact ticks whose force its safety clamped
  std::int64_t haptic_ticks{0};
  double max_force_limit_n{0.0};  ///< its device's force limit (its safety's, N)
  haptics::SafetyCounters safety;
};

/// What a run measured.
struct SessionReport {
  double simulated_s{0.0};
  std::int64_t haptic_ticks{0};
  std::int64_t simulation_steps{0};
  double wall_s{0.0};
  double simulation_steps_per_s{0.0};       ///< achieved (wall clock)
  int simulation_threads{1};                ///< threads a body's steps ran on (real time; the last body's)
  std::string cpu_placement{"not pinned"};  ///< real time: which CPUs the threads were kept on
  /// Simulation steps per second of wall time in the thesis' three states (the rate a
  /// graphics loop showing each new shape could reach): untouched and at rest, deforming
  /// without contact, in contact.
  double rate_untouched{0.0}, rate_deforming{0.0}, rate_in_contact{0.0};
  double max_force_n{0.0};
  double contact_time_s{0.0};
  std::int64_t fall_through_events{0};    ///< steps whose proxy was inside a closed body (not counting a start inside)
  std::int64_t clamped_contact_ticks{0};  ///< contact ticks whose force was clamped by safety
  bool diverged{false};
  std::string divergence;
  /// Why the run ended early because the device failed (unplugged, its SDK in error); empty
  /// when it did not. Its force was faded to zero first.
  std::string device_failure;
  double max_displacement_m{0.0};
  /// Contact between bodies: the contacts within the contact distance at the last pass, and
  /// the most at any pass of the run.
  std::int64_t body_contacts{0}, max_body_contacts{0};
  /// The scene asked for ContactResponse::kFrictionConstraint, which is not built yet: its
  /// contacts were solved as penalty springs, without friction.
  bool friction_solved_as_penalty{false};
  std::vector<BodyReport> bodies;
  /// Every hand, the first first (its figures are the ones above, which stay the first hand's).
  std::vector<HandReport> hands;
  std::vector<std::string> applied_commands;  ///< "step N: what", in order
  haptics::PeriodStats haptic_periods;
  haptics::SafetyCounters safety;
};

// The command seam (command::SetParameter, ..., Command, ParameterChange): command_seam.h.

namespace detail {
struct World;
class SnapshotPublisher;
class SessionRunner;
}  // namespace detail

class Session {
 public:
  /// One device: the first hand only (config.more_hands is left out).
  static Expected<std::unique_ptr<Session>> make(std::vector<SessionBody> bodies,
                                                 std::unique_ptr<haptics::Device> device, const SessionConfig& config);
  /// Several hands: `more_devices[i]` is the device of config.more_hands[i].
  static Expected<std::unique_ptr<Session>> make(std::vector<SessionBody> bodies,
                                                 std::unique_ptr<haptics::Device> device,
                                                 std::vector<std::unique_ptr<haptics::Device>> more_devices,
                                                 const SessionConfig& config);
  /// One deformable body (the common case).
  static Expected<std::unique_ptr<Session>> make(SessionBody body, std::unique_ptr<haptics::Device> device,
                                                 const SessionConfig& config);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  /// Runs `seconds` of virtual time in lock-step, from where the last virtual run ended. `on_sample` receives every
  /// haptic tick's sample (for telemetry); `progress` is told how far along the run is.
  SessionReport run_virtual(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                            const ProgressSink& progress = {});

  /// Runs `seconds` of wall time: start_realtime(), poll() until then, stop_realtime().
  SessionReport run_realtime(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                             const ProgressSink& progress = {});

  /// Real time, for a supervisor that runs its own loop (the window): starts the haptic
  /// thread and the simulation thread and returns at once.
  void start_realtime();
  /// Hands the telemetry gathered since the last call to `on_sample` (supervisor thread).
  void poll(const std::function<void(const haptics::HapticSample&)>& on_sample);
  /// Stops both threads (joins) and returns the report. Idempotent.
  SessionReport stop_realtime(const std::function<void(const haptics::HapticSample&)>& on_sample = {});
  [[nodiscard]] bool realtime_running() const;
  /// The simulation thread has ended on its own (it diverged): stop_realtime() says why.
  [[nodiscard]] bool simulation_ended() const;
  /// Real time: pace the simulation to the wall clock (true, the default) or step as fast as
  /// it goes (the haptic loop still runs at its own rate). Any thread.
  void set_realtime_pacing(bool paced);
  [[nodiscard]] bool realtime_pacing() const;
  /// Simulation steps taken since the session was made (any thread: for a live steps/s).
  [[nodiscard]] std::uint64_t steps_taken() const;

  /// The command seam: validates `command` now (a clear error, nothing changed, when it is
  /// wrong) and queues it; the simulation applies it before its next step. Any thread.
  Expected<void> submit(const Command& command);
  /// A parameter's value as the commands accepted so far leave it (applied, or queued for the
  /// next step). Errors: no such body, a body without mechanics, no such parameter.
  [[nodiscard]] Expected<double> parameter(BodyId body, mechanics::ParameterRef parameter) const;
  /// A deformable body's model configuration as the commands accepted so far leave it (to
  /// resolve a scene's parameter names against). Errors: no such body, a rigid body.
  [[nodiscard]] Expected<mechanics::ModelConfig> body_config(BodyId body) const;
  /// Asks a run in progress (run_virtual, run_realtime) to end after the current step; the
  /// run returns its report as far as it went. Any thread (a Ctrl-C handler, a supervisor).
  /// The next run clears it.
  void request_stop();
  /// Parameters changed through submit() so far, in order (to save with the project): those
  /// the simulation has applied, and with `with_queued` those accepted for the next step too.
  [[nodiscard]] std::vector<ParameterChange> parameter_changes(bool with_queued = false) const;
  /// Surface materials set through submit() so far, by body name, in order.
  [[nodiscard]] std::vector<MaterialChange> material_changes() const;

  [[nodiscard]] std::size_t body_count() const;
  [[nodiscard]] const SessionBody& body(std::size_t i) const;
  /// Index of the body a snapshot triangle (of haptic layer `layer`) belongs to (-1 if none).
  [[nodiscard]] std::int32_t body_of_triangle(std::int32_t triangle, std::int32_t layer = 0) const;
  /// Point of snapshot triangle `t` at weights `w` in the rest shape (for indentation).
  [[nodiscard]] Vec3 rest_point(std::int32_t t, const Vec3& w, std::int32_t layer = 0) const;
  [[nodiscard]] std::size_t layer_count() const;
  /// Mechanical state of body i (deformable bodies; read it when no run is going on).
  [[nodiscard]] const mechanics::MechanicalState& state(std::size_t i) const;
  /// The first body (single-body callers).
  [[nodiscard]] const mechanics::MechanicalModel& model() const { return *body(0).model; }
  [[nodiscard]] const mechanics::MechanicalState& state() const { return state(0); }
  [[nodiscard]] const SessionBody& body() const { return body(0); }
  /// Latest surface snapshot of a haptic layer, for a reader thread (one reader: the window).
  /// Published with every step from the first call on (before it, nothing is copied for it).
  TripleBuffer<haptics::SurfaceSnapshot>& graphics_surfaces(std::size_t layer = 0);
  /// Latest node positions of every body (3N flat; empty for a rigid body), for a reader
  /// thread (the window's stress colours). Published with every step from the first call on.
  TripleBuffer<std::vector<std::vector<double>>>& graphics_states();
  /// The last contact pass's contacts between bodies with their forces, for a reader thread
  /// (the window's contact view). Published with every step from the first call on.
  TripleBuffer<BodyContactsView>& graphics_contacts();
  /// Simulated time of the world so far, s (read it when no run is going on).
  [[nodiscard]] double simulated_time() const;
  /// The world simulation step dt (the smallest body dt), s.
  [[nodiscard]] double dt() const;
  /// The calibration in force (the configuration's, or the last SetCalibration submitted).
  [[nodiscard]] haptics::Calibration calibration() const;
  /// SetCalibration commands the simulation has passed to the haptic loop so far (any thread:
  /// a caller that moves a stylus in device coordinates waits for its change to arrive).
  [[nodiscard]] std::uint64_t calibrations_applied() const;
  /// The first hand's haptic loop.
  [[nodiscard]] const haptics::HapticLoop& haptic_loop() const;
  /// Hands: 1 + config.more_hands.size(); hand 0 is haptic_loop().
  [[nodiscard]] std::size_t hand_count() const;
  [[nodiscard]] const haptics::HapticLoop& haptic_loop(std::size_t hand) const;

 private:
  Session(std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device,
          std::vector<std::unique_ptr<haptics::Device>> more_devices, const SessionConfig& config);

  // The world and the parts that step it (coupling/detail/): the seam's commands reach the
  // world through step_world(), which the runner calls; the publisher makes its snapshots.
  std::unique_ptr<detail::World> world_;
  std::unique_ptr<detail::SnapshotPublisher> publisher_;
  std::unique_ptr<CommandSeam> seam_;
  std::unique_ptr<detail::SessionRunner> runner_;
};

}  // namespace hof::coupling
