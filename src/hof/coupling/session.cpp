#include "hof/coupling/session.h"

#include <fmt/format.h>

#include <algorithm>

#include "hof/coupling/detail/session_runner.h"
#include "hof/coupling/detail/snapshot_publisher.h"
#include "hof/coupling/detail/world_step.h"

namespace hof::coupling {

Session::Session(std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device,
                 std::vector<std::unique_ptr<haptics::Device>> more_devices, const SessionConfig& config)
    : world_(std::make_unique<detail::World>()) {
  detail::init_world(*world_, std::move(bodies), std::move(device), config, std::move(more_devices));
  publisher_ = std::make_unique<detail::SnapshotPublisher>(*world_);
  seam_ = std::make_unique<CommandSeam>(*world_);
  runner_ = std::make_unique<detail::SessionRunner>(*world_, *seam_, *publisher_);
}

Session::~Session() {
  stop_realtime();
  // The runner and the publisher hold the world: they go first.
  runner_.reset();
  publisher_.reset();
}

Expected<std::unique_ptr<Session>> Session::make(SessionBody body, std::unique_ptr<haptics::Device> device,
                                                 const SessionConfig& config) {
  std::vector<SessionBody> bodies;
  bodies.push_back(std::move(body));
  return make(std::move(bodies), std::move(device), config);
}

Expected<std::unique_ptr<Session>> Session::make(std::vector<SessionBody> bodies,
                                                 std::unique_ptr<haptics::Device> device, const SessionConfig& config) {
  // One device given: the first hand only (a caller that opens no other device, the window).
  if (config.more_hands.empty()) return make(std::move(bodies), std::move(device), {}, config);
  SessionConfig first_hand = config;
  first_hand.more_hands.clear();
  return make(std::move(bodies), std::move(device), {}, first_hand);
}

Expected<std::unique_ptr<Session>> Session::make(std::vector<SessionBody> bodies,
                                                 std::unique_ptr<haptics::Device> device,
                                                 std::vector<std::unique_ptr<haptics::Device>> more_devices,
                                                 const SessionConfig& config) {
  if (!device) return make_error(ErrorCode::kInvalidArgument, "session: no device");
  if (more_devices.size() != config.more_hands.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("session: {} more hand(s) configured but {} device(s) given for them",
                                  config.more_hands.size(), more_devices.size()));
  }
  for (std::size_t h = 0; h < more_devices.size(); ++h) {
    const HandConfig& hand = config.more_hands[h];
    const std::string name = fmt::format("session: hand {} ({})", h + 2, hand.device);
    if (!more_devices[h]) return make_error(ErrorCode::kInvalidArgument, name + ": no device");
    if (more_devices[h].get() == device.get()) {
      return make_error(ErrorCode::kInvalidArgument, name + ": the same device as the first hand");
    }
    // Virtual time ticks every hand in lock-step with the simulation.
    if (hand.haptics.rate_hz != config.haptics.rate_hz) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: haptic rate {} Hz, the first hand's is {} Hz (every hand ticks at one rate)",
                                    name, hand.haptics.rate_hz, config.haptics.rate_hz));
    }
    if (hand.tool && hand.tool == config.tool) {
      return make_error(ErrorCode::kInvalidArgument, name + ": carries the first hand's tool (each hand its own)");
    }
    for (std::size_t k = 0; k < h; ++k) {
      if (hand.tool && hand.tool == config.more_hands[k].tool) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("{}: carries hand {}'s tool (each hand its own)", name, k + 2));
      }
    }
  }
  for (const SessionBody& body : bodies) {
    if (body.deformable() && body.mapping.surface_vertex_count() != body.surface.vertices.size()) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("session: body '{}': the surface has {} vertices but the mapping {}", body.name,
                                    body.surface.vertices.size(), body.mapping.surface_vertex_count()));
    }
    if (body.material) {
      if (auto ok = haptics::validate(*body.material); !ok) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("session: body '{}': {}", body.name, ok.error().message));
      }
    }
  }
  if (!(config.haptics.rate_hz >= 100.0 && config.haptics.rate_hz <= 20000.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("session: haptic rate must be in [100, 20000] Hz, got {}", config.haptics.rate_hz));
  }
  if (auto ok = haptics::validate_effects(config.effects); !ok) return std::unexpected(ok.error());
  if (auto ok = detail::validate_contacts(config.contacts, bodies); !ok) return std::unexpected(ok.error());
  if (config.coupling == ContactCoupling::kFemReaction) {
    for (const SessionBody& body : bodies) {
      if (body.deformable() && !detail::fem_reaction_step_fits(body.model->dt_s, config.haptics.rate_hz)) {
        return make_error(
            ErrorCode::kInvalidArgument,
            fmt::format("session: coupling fem-reaction steps the simulation once per haptic tick: body '{}' has dt "
                        "{:g} s, the haptic period is {:g} s (set dt to it, or use another coupling)",
                        body.name, body.model->dt_s, 1.0 / config.haptics.rate_hz));
      }
    }
  }
  auto session =
      std::unique_ptr<Session>(new Session(std::move(bodies), std::move(device), std::move(more_devices), config));
  session->publisher_->publish(0.0);
  return session;
}

// ---- Running (session_runner.cpp)

SessionReport Session::run_virtual(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                                   const ProgressSink& progress) {
  return runner_->run_virtual(seconds, on_sample, progress);
}

SessionReport Session::run_realtime(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                                    const ProgressSink& progress) {
  return runner_->run_realtime(seconds, on_sample, progress);
}

void Session::start_realtime() { runner_->start_realtime(); }
void Session::poll(const std::function<void(const haptics::HapticSample&)>& on_sample) { runner_->poll(on_sample); }
SessionReport Session::stop_realtime(const std::function<void(const haptics::HapticSample&)>& on_sample) {
  return runner_->stop_realtime(on_sample);
}
bool Session::realtime_running() const { return runner_->realtime_running(); }
bool Session::simulation_ended() const { return runner_->simulation_ended(); }
void Session::set_realtime_pacing(bool paced) { runner_->set_pacing(paced); }
bool Session::realtime_pacing() const { return runner_->pacing(); }
void Session::request_stop() { runner_->request_stop(); }
std::uint64_t Session::steps_taken() const { return world_->steps_taken.load(std::memory_order_relaxed); }

// ---- The command seam (command_seam.cpp)

Expected<void> Session::submit(const Command& command) { return seam_->submit(command); }
Expected<double> Session::parameter(BodyId body, mechanics::ParameterRef parameter) const {
  return seam_->parameter(body, parameter);
}
Expected<mechanics::ModelConfig> Session::body_config(BodyId body) const { return seam_->body_config(body); }
std::vector<ParameterChange> Session::parameter_changes(bool with_queued) const {
  return seam_->parameter_changes(with_queued);
}
std::vector<MaterialChange> Session::material_changes() const { return seam_->material_changes(); }
haptics::Calibration Session::calibration() const { return seam_->calibration(); }
std::uint64_t Session::calibrations_applied() const {
  return world_->calibrations_applied.load(std::memory_order_acquire);
}

// ---- The world, read

std::size_t Session::body_count() const { return world_->bodies.size(); }
const SessionBody& Session::body(std::size_t i) const { return world_->bodies[i].body; }
const mechanics::MechanicalState& Session::state(std::size_t i) const { return world_->bodies[i].state; }
std::size_t Session::layer_count() const { return world_->layers.size(); }
double Session::simulated_time() const { return world_->time_s; }
double Session::dt() const { return world_->dt.load(std::memory_order_relaxed); }
const haptics::HapticLoop& Session::haptic_loop() const { return *world_->loop; }
std::size_t Session::hand_count() const { return detail::hand_count(*world_); }
const haptics::HapticLoop& Session::haptic_loop(std::size_t hand) const {
  return detail::hand_loop(*world_, std::min(hand, detail::hand_count(*world_) - 1));
}

std::int32_t Session::body_of_triangle(std::int32_t triangle, std::int32_t layer) const {
  if (layer < 0 || static_cast<std::size_t>(layer) >= world_->layers.size()) return -1;
  const haptics::SurfaceSnapshot& rest = world_->layers[static_cast<std::size_t>(layer)]->rest;
  const std::int32_t part = rest.part_of(triangle);
  return part < 0 ? -1 : rest.parts[static_cast<std::size_t>(part)].body;
}

Vec3 Session::rest_point(std::int32_t triangle, const Vec3& weights, std::int32_t layer) const {
  if (layer < 0 || static_cast<std::size_t>(layer) >= world_->layers.size()) return Vec3::Zero();
  const haptics::SurfaceSnapshot& rest = world_->layers[static_cast<std::size_t>(layer)]->rest;
  if (triangle < 0 || static_cast<std::size_t>(triangle) >= rest.triangles.size()) return Vec3::Zero();
  return rest.point(triangle, weights);
}

TripleBuffer<haptics::SurfaceSnapshot>& Session::graphics_surfaces(std::size_t layer) {
  return publisher_->graphics_surfaces(layer);
}

TripleBuffer<std::vector<std::vector<double>>>& Session::graphics_states() { return publisher_->graphics_states(); }

TripleBuffer<BodyContactsView>& Session::graphics_contacts() { return publisher_->graphics_contacts(); }

}  // namespace hof::coupling
