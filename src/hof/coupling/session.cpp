#include "hof/coupling/session.h"

#include <fmt/format.h>

#include "hof/coupling/detail/session_runner.h"
#include "hof/coupling/detail/snapshot_publisher.h"
#include "hof/coupling/detail/world_step.h"

namespace hof::coupling {

Session::Session(std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device, const SessionConfig& config)
    : world_(std::make_unique<detail::World>()) {
  detail::init_world(*world_, std::move(bodies), std::move(device), config);
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
  if (!device) return make_error(ErrorCode::kInvalidArgument, "session: no device");
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
  auto session = std::unique_ptr<Session>(new Session(std::move(bodies), std::move(device), config));
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
