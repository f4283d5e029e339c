#pragma once
/// @file
/// The command seam: the typed changes a supervisor (the `hof run` command, the window, a
/// script) makes to a running session, and the queue that carries them to the simulation.
/// Each command type has a validate (on the submitting thread: a clear error, nothing
/// changed, when it is wrong) and an apply (on the simulation thread, between two steps).
///
/// Threads: accepted commands reach the simulation through a lock-free single-producer
/// single-consumer ring (core/spsc_ring.h). The submitting side may be several threads (the
/// window and its script runner): they take turns through a small mutex on the producer side
/// only, which makes them one producer. The simulation (the consumer) never locks: what it
/// must tell the submitting side (a parameter applied or refused, a model swapped in) goes
/// back through a second ring, read by the submitting side under its mutex. A full ring is a
/// clear error from submit(), never a wait. The haptic tick never touches the seam: what it
/// must know arrives as haptics::HapticSettings.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/spsc_ring.h"
#include "hof/haptics/device_config.h"
#include "hof/haptics/haptic_loop.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/model_parameters.h"

namespace hof::coupling {

struct SessionReport;
namespace detail {
struct World;
}

/// A body of a session, by its index (Session::body(i)); scene::body_id maps a scene's name to
/// it.
enum class BodyId : std::uint32_t {};

namespace command {
/// A parameter of a body's component (scene::resolve_parameter maps a scene's names to it).
struct SetParameter {
  BodyId body{};
  mechanics::ParameterRef parameter;
  double value{0.0};
};
struct Pause {};
struct Resume {};
struct SingleStep {
  int steps{1};
};
struct Reset {};
/// The haptic surface of one body, or of every body (nullopt).
struct SetMaterial {
  std::optional<BodyId> body;
  haptics::SurfaceMaterial material;
};
struct SetEffects {
  haptics::ForceEffects effects;
};
struct SetRenderer {
  haptics::RendererConfig renderer;
};
/// A force limit below the device's (haptics::SafetyConfig::max_force_n; 0: the device's).
struct SetForceLimit {
  double max_force_n{0.0};
};
/// Another device (a typed configuration, see haptics::open_device; users' spec strings are
/// parsed by scene::parse_device_spec): opened when submitted (a device that is not there is
/// refused then), switched to between two ticks with its own force limit.
struct SetDevice {
  haptics::DeviceConfig config;
  /// How the applied-commands log names the device (the spec the user typed).
  std::string label;
  /// Filled by submit(); a caller that opened the device itself (to keep a handle on it, as
  /// the window does for the mouse, or to name its spec in an error) passes it here.
  std::shared_ptr<haptics::Device> opened;
};
/// Another device calibration (device → world), e.g. the window's "fit the workspace to the
/// scene": the proxy restarts at the next reading. The linear part must be invertible.
struct SetCalibration {
  haptics::Calibration calibration;
};
/// Another model for a deformable body, on the same mesh (a structural edit: a force field,
/// solver, mass or constraint switched, added or removed; material regions). Built and
/// checked when submitted (on the caller's thread); the simulation swaps it in between two
/// steps, from the body's current shape and motion. The body's earlier parameter changes are
/// taken as part of `config` (parameter_changes() forgets them).
struct SetModel {
  BodyId body{};
  mechanics::ModelConfig config;
  /// Filled by submit(): the model built from `config`.
  std::shared_ptr<mechanics::MechanicalModel> built;
};
/// Contact between two bodies switched off, or on again (ContactSettings::disabled_pairs),
/// from the next step: the window's pair switch. Both bodies must take part in contact between
/// bodies (BodyCollision::enabled), and the session's contact must be on; a pair is two
/// different bodies (as a project's <contact><pair>: self-collision is a body's own setting).
struct SetContactPair {
  BodyId a{};
  BodyId b{};
  bool enabled{true};
};
}  // namespace command
using Command =
    std::variant<command::SetParameter, command::Pause, command::Resume, command::SingleStep, command::Reset,
                 command::SetMaterial, command::SetEffects, command::SetRenderer, command::SetForceLimit,
                 command::SetDevice, command::SetModel, command::SetCalibration, command::SetContactPair>;

/// A parameter changed through the seam, to be saved with the project (scene::parameter_changes
/// names it for the file: the project's <set>).
struct ParameterChange {
  BodyId body{};
  mechanics::ParameterRef parameter;
  double value{0.0};
};
/// A body's haptic surface changed through the seam (command::SetMaterial).
struct MaterialChange {
  BodyId body{};
  haptics::SurfaceMaterial material;
};

/// Commands that can wait in the seam at once (submitted, not yet applied).
inline constexpr std::size_t kCommandQueueCapacity = 1024;

namespace detail {
// What the simulation tells the submitting side about a command it applied (at namespace
// scope: the ring's element must be default-constructible where the seam is declared).
enum class SeamOutcome : std::uint8_t { kApplied, kRefused, kModelSwapped };
struct SeamReport {
  std::uint64_t ticket{0};
  SeamOutcome outcome{SeamOutcome::kApplied};
  std::uint32_t body{0};
  mechanics::ModelConfig* running{nullptr};  // kRefused: the config that runs (owned, handed over)
};
}  // namespace detail

/// The seam of one session. submit() and the queries run on any thread but the simulation's;
/// apply() runs on the simulation's, between two steps.
class CommandSeam {
 public:
  /// The session's bodies, coupling and haptic rate as the world was made.
  explicit CommandSeam(const detail::World& world);
  ~CommandSeam();
  CommandSeam(const CommandSeam&) = delete;
  CommandSeam& operator=(const CommandSeam&) = delete;

  /// Validates `command` (a clear error, nothing changed, when it is wrong) and queues it.
  Expected<void> submit(const Command& command);
  /// Applies the queued commands, in order, to `world` (simulation thread, between steps).
  void apply(detail::World& world, SessionReport& report);

  [[nodiscard]] Expected<double> parameter(BodyId body, mechanics::ParameterRef parameter) const;
  [[nodiscard]] Expected<mechanics::ModelConfig> body_config(BodyId body) const;
  [[nodiscard]] std::vector<ParameterChange> parameter_changes(bool with_queued) const;
  [[nodiscard]] std::vector<MaterialChange> material_changes() const;
  [[nodiscard]] haptics::Calibration calibration() const;

 private:
  // Validation, one per command type (under mutex_): a command may be completed here (a device
  // opened, a model built) and the seam's view of the bodies updated.
  Expected<void> validate(command::SetParameter& set);
  Expected<void> validate(command::SetModel& model);
  Expected<void> validate(command::SetCalibration& calibration);
  Expected<void> validate(command::SingleStep& steps);
  Expected<void> validate(command::SetMaterial& material);
  Expected<void> validate(command::SetEffects& effects);
  Expected<void> validate(command::SetForceLimit& limit);
  Expected<void> validate(command::SetRenderer& renderer);
  Expected<void> validate(command::SetContactPair& pair);
  Expected<void> validate(command::SetDevice&) { return {}; }
  Expected<void> validate(command::Pause&) { return {}; }
  Expected<void> validate(command::Resume&) { return {}; }
  Expected<void> validate(command::Reset&) { return {}; }
  // Application, one per command type (simulation thread). False: the command must wait for
  // the next step (and the ones after it with it).
  struct Applying;
  bool apply(const command::SetParameter& set, Applying& a);
  bool apply(const command::SetModel& model, Applying& a);
  bool apply(const command::Pause&, Applying& a);
  bool apply(const command::Resume&, Applying& a);
  bool apply(const command::SingleStep& steps, Applying& a);
  bool apply(const command::Reset&, Applying& a);
  bool apply(const command::SetMaterial& material, Applying& a);
  bool apply(const command::SetEffects& effects, Applying& a);
  bool apply(const command::SetRenderer& renderer, Applying& a);
  bool apply(const command::SetCalibration& calibration, Applying& a);
  bool apply(const command::SetForceLimit& limit, Applying& a);
  bool apply(const command::SetDevice& device, Applying& a);
  bool apply(const command::SetContactPair& pair, Applying& a);
  [[nodiscard]] std::string body_names() const;
  // The index of a body that has mechanics; errors name the body (`rigid`: why a rigid body is refused).
  [[nodiscard]] Expected<std::size_t> deformable_body(BodyId body, std::string_view rigid) const;

  std::vector<std::string> names_;   // the bodies' names (fixed)
  std::vector<char> has_mechanics_;  // per body, fixed: a model and its config
  std::vector<char> collides_;       // per body, fixed: it takes part in contact between bodies
  bool contacts_enabled_{false};     // the session's contact between bodies is on (fixed)
  bool fem_reaction_{false};         // the coupling needs dt equal to the haptic period
  double haptic_rate_hz_{1000.0};
  // A parameter command accepted, in submission order (applied: it is a change to save).
  struct Accepted {
    std::uint64_t ticket{0};
    ParameterChange change;
    bool applied{false};
  };
  using Outcome = detail::SeamOutcome;
  using Report = detail::SeamReport;
  // A command on its way: the ticket orders the simulation's reports with the log.
  struct Queued {
    std::uint64_t ticket{0};
    Command command;
  };
  void take_reports() const;   // the simulation's reports since the last call (under mutex_)
  void tell(const Report& r);  // simulation side: a report to the submitting side

  // ---- Producer side: under mutex_ (mutable: the const queries read the reports first).
  mutable std::mutex mutex_;
  std::uint64_t next_ticket_{1};
  std::uint64_t pushed_{0};
  mutable std::vector<Accepted> accepted_;
  haptics::Calibration submitted_calibration_;
  std::vector<MaterialChange> material_changes_;
  mutable std::vector<mechanics::ModelConfig> validated_configs_;  // configs as the accepted commands leave them
  // ---- The rings (each owned pointer is handed from one side to the other).
  SpscRing<Queued*> queue_{kCommandQueueCapacity};           // submitting side → simulation
  mutable SpscRing<Report> reports_{kCommandQueueCapacity};  // simulation → submitting side
  std::atomic<std::uint64_t> popped_{0};                     // commands the simulation has taken off the queue
  // ---- Consumer side (simulation thread only).
  Queued* waiting_{nullptr};  // a command that waits for the next step (a device switch)
  std::uint64_t applying_ticket_{0};
};

}  // namespace hof::coupling
