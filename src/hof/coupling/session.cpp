#include "hof/coupling/session.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <thread>

#include "hof/mechanics/step.h"
#include "hof/mesh/surface_check.h"

namespace hof::coupling {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace

Session::Session(SessionBody body, std::unique_ptr<haptics::Device> device, const SessionConfig& config)
    : body_(std::move(body)),
      device_(std::move(device)),
      config_(config),
      state_(mechanics::make_state(body_.model)),
      surfaces_(haptics::make_snapshot(body_.surface, config.tree)) {
  surface_positions_.assign(body_.surface.vertices.size(), Vec3::Zero());
  surface_velocities_.assign(body_.surface.vertices.size(), Vec3::Zero());
  loop_ = std::make_unique<haptics::HapticLoop>(*device_, surfaces_, config_.haptics);
  surface_closed_ = mesh::check_surface(body_.surface).closed_manifold();
  loop_->effects() = config_.effects;
}

Expected<std::unique_ptr<Session>> Session::make(SessionBody body, std::unique_ptr<haptics::Device> device,
                                                 const SessionConfig& config) {
  if (!device) return make_error(ErrorCode::kInvalidArgument, "session: no device");
  if (body.mapping.surface_vertex_count() != body.surface.vertices.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("session '{}': the surface has {} vertices but the mapping {}", body.name,
                                  body.surface.vertices.size(), body.mapping.surface_vertex_count()));
  }
  if (!(config.haptics.rate_hz >= 100.0 && config.haptics.rate_hz <= 20000.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("session: haptic rate must be in [100, 20000] Hz, got {}", config.haptics.rate_hz));
  }
  auto session = std::unique_ptr<Session>(new Session(std::move(body), std::move(device), config));
  session->publish_surface(0.0);
  return session;
}

void Session::publish_surface(double time_s) {
  body_.mapping.apply({state_.x.data(), static_cast<std::size_t>(state_.x.size())}, surface_positions_);
  body_.mapping.apply({state_.v.data(), static_cast<std::size_t>(state_.v.size())}, surface_velocities_);
  haptics::SurfaceSnapshot& slot = surfaces_.write_slot();
  haptics::update_snapshot(slot, surface_positions_, surface_velocities_, time_s);
  slot.local.valid = false;
  if (config_.coupling == ContactCoupling::kCompliance && last_triangle_ >= 0 && contact_ticks_since_publish_ > 0) {
    // The contact point's compliance at the current state (Saupin, Duriez & Cotin 2008).
    const mesh::Tri& tri = body_.surface.triangles[static_cast<std::size_t>(last_triangle_)];
    const std::array<std::int32_t, 3> vertices{tri[0], tri[1], tri[2]};
    const std::array<double, 3> bary{last_barycentric_[0], last_barycentric_[1], last_barycentric_[2]};
    std::array<std::int32_t, 12> nodes{};
    std::array<double, 12> weights{};
    const std::size_t count = body_.mapping.point_weights(vertices, bary, nodes, weights);
    Mat3 compliance;
    if (mechanics::compute_point_compliance(body_.model, state_, std::span(nodes.data(), count),
                                            std::span(weights.data(), count), compliance)) {
      const Eigen::FullPivLU<Mat3> lu(compliance);
      if (lu.isInvertible()) {
        slot.local.valid = true;
        slot.local.triangle = last_triangle_;
        slot.local.barycentric = last_barycentric_;
        slot.local.compliance = compliance;
        slot.local.stiffness = lu.inverse();
        // The load that holds the tissue in its current shape at that point (minus its
        // elastic force), rather than the force last applied: the local model then stays
        // consistent with the simulated shape even while the simulation is still settling.
        slot.local.applied_force =
            -mechanics::point_elastic_force(body_.model, state_, std::span(nodes.data(), count), std::span(weights.data(), count));
      }
    }
  }
  contact_ticks_since_publish_ = 0;
  surfaces_.publish();
}

void Session::accumulate(const haptics::HapticSample& s) {
  ++ticks_since_step_;
  if (s.valid) {
    last_proxy_ = s.proxy;
    last_proxy_valid_ = true;
  }
  if (!s.contact || s.triangle < 0) return;
  reaction_sum_ -= s.force;  // the tissue feels the opposite of what the hand feels
  ++contact_ticks_;
  ++contact_ticks_since_publish_;
  last_triangle_ = s.triangle;
  last_barycentric_ = s.barycentric;
}

void Session::apply_contact_forces() {
  state_.external_force.setZero();
  last_reaction_.setZero();
  if (contact_ticks_ > 0 && last_triangle_ >= 0) {
    // Average over the step's ticks (the force acted only during the contact ticks).
    const Vec3 reaction = reaction_sum_ / static_cast<double>(std::max(ticks_since_step_, 1));
    last_reaction_ = reaction;
    const mesh::Tri& tri = body_.surface.triangles[static_cast<std::size_t>(last_triangle_)];
    std::span<double> forces{state_.external_force.data(), static_cast<std::size_t>(state_.external_force.size())};
    if (config_.coupling == ContactCoupling::kClosestVertex) {
      int nearest = 0;
      for (int k = 1; k < 3; ++k) {
        if (last_barycentric_[k] > last_barycentric_[nearest]) nearest = k;
      }
      body_.mapping.add_vertex_force(tri[nearest], reaction, forces);
    } else {
      for (int k = 0; k < 3; ++k) body_.mapping.add_vertex_force(tri[k], last_barycentric_[k] * reaction, forces);
    }
  }
  reaction_sum_.setZero();
  contact_ticks_ = 0;
  ticks_since_step_ = 0;
}

bool Session::proxy_inside(const Vec3& p) const {
  // "Inside" only means something for a closed surface (an open sheet has no inside).
  if (!surface_closed_) return false;
  // Generalised winding number of the current surface at p (Van Oosterom & Strackee 1983).
  double total = 0.0;
  for (const mesh::Tri& t : body_.surface.triangles) {
    const Vec3 a = surface_positions_[t[0]] - p, b = surface_positions_[t[1]] - p, c = surface_positions_[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    total += 2.0 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return total / (4.0 * std::numbers::pi) > 0.5;
}

struct Session::StateTimer {
  double untouched_s{0}, deforming_s{0}, contact_s{0};
  std::int64_t untouched{0}, deforming{0}, contact{0};
  void add(bool in_contact, bool moving, double seconds) {
    if (in_contact) {
      contact_s += seconds;
      ++contact;
    } else if (moving) {
      deforming_s += seconds;
      ++deforming;
    } else {
      untouched_s += seconds;
      ++untouched;
    }
  }
  static double rate(std::int64_t n, double s) { return s > 0.0 ? static_cast<double>(n) / s : 0.0; }
};

void Session::finish_report(SessionReport& report, const StateTimer& timer, double wall_s) const {
  report.wall_s = wall_s;
  report.simulated_s = static_cast<double>(report.simulation_steps) * body_.model.dt_s;
  report.simulation_steps_per_s = wall_s > 0.0 ? static_cast<double>(report.simulation_steps) / wall_s : 0.0;
  report.rate_untouched = StateTimer::rate(timer.untouched, timer.untouched_s);
  report.rate_deforming = StateTimer::rate(timer.deforming, timer.deforming_s);
  report.rate_in_contact = StateTimer::rate(timer.contact, timer.contact_s);
  report.haptic_periods = loop_->period_stats();
  report.safety = loop_->safety_counters();
  for (std::size_t i = 0; i < body_.model.node_count(); ++i) {
    report.max_displacement_m = std::max(report.max_displacement_m,
                                         (state_.position(static_cast<std::int32_t>(i)) - body_.model.rest_positions[i]).norm());
  }
}

SessionReport Session::run_virtual(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                                   const ProgressSink& progress) {
  SessionReport report;
  const double dt = body_.model.dt_s;
  const double tick_period = 1.0 / config_.haptics.rate_hz;
  const auto ticks_per_step = std::max<std::int64_t>(1, std::llround(dt / tick_period));
  const auto steps = static_cast<std::int64_t>(std::ceil(seconds / dt - 1e-9));
  const auto start = Clock::now();
  StateTimer timer;
  haptics::HapticSample sample;
  std::int64_t tick = 0;
  for (std::int64_t s = 0; s < steps; ++s) {
    bool contact_this_step = false;
    for (std::int64_t k = 0; k < ticks_per_step; ++k, ++tick) {
      loop_->tick(static_cast<double>(tick) * tick_period);
      while (loop_->telemetry().pop(sample)) {
        accumulate(sample);
        contact_this_step = contact_this_step || sample.contact;
        report.max_force_n = std::max(report.max_force_n, sample.force.norm());
        if (sample.contact) report.contact_time_s += tick_period;
        if (on_sample) on_sample(sample);
      }
    }
    // Fall-through: the proxy against the surface the haptic loop rendered on.
    if (last_proxy_valid_ && proxy_inside(last_proxy_)) ++report.fall_through_events;
    const auto step_start = Clock::now();
    apply_contact_forces();
    if (!mechanics::step(body_.model, state_)) {
      report.diverged = true;
      report.divergence = fmt::format("{} at step {}: {}", state_.divergence.component, state_.divergence.step,
                                      state_.divergence.reason);
      break;
    }
    publish_surface(static_cast<double>(s + 1) * dt);
    const double moving = state_.v.size() ? state_.v.cwiseAbs().maxCoeff() : 0.0;
    timer.add(contact_this_step, moving > 1e-4, seconds_between(step_start, Clock::now()));
    ++report.simulation_steps;
    if (progress && (s % 16 == 0 || s + 1 == steps)) progress("haptic session (virtual time)", static_cast<double>(s + 1) / static_cast<double>(steps));
  }
  report.haptic_ticks = tick;
  finish_report(report, timer, seconds_between(start, Clock::now()));
  return report;
}

SessionReport Session::run_realtime(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                                    const ProgressSink& progress) {
  SessionReport report;
  const double dt = body_.model.dt_s;
  StateTimer timer;
  haptics::HapticSample sample;
  const auto start = Clock::now();
  loop_->start();
  auto next = start;
  std::int64_t s = 0;
  for (;; ++s) {
    const double elapsed = seconds_between(start, Clock::now());
    if (elapsed >= seconds) break;
    bool contact_this_step = false;
    while (loop_->telemetry().pop(sample)) {
      accumulate(sample);
      contact_this_step = contact_this_step || sample.contact;
      report.max_force_n = std::max(report.max_force_n, sample.force.norm());
      if (sample.contact) report.contact_time_s += loop_->nominal_period_s();
      if (on_sample) on_sample(sample);
    }
    if (last_proxy_valid_ && proxy_inside(last_proxy_)) ++report.fall_through_events;
    const auto step_start = Clock::now();
    apply_contact_forces();
    if (!mechanics::step(body_.model, state_)) {
      report.diverged = true;
      report.divergence = fmt::format("{} at step {}: {}", state_.divergence.component, state_.divergence.step,
                                      state_.divergence.reason);
      break;
    }
    publish_surface(seconds_between(start, Clock::now()));
    const double moving = state_.v.size() ? state_.v.cwiseAbs().maxCoeff() : 0.0;
    timer.add(contact_this_step, moving > 1e-4, seconds_between(step_start, Clock::now()));
    ++report.simulation_steps;
    if (progress && s % 16 == 0) progress("haptic session (real time)", std::min(1.0, elapsed / seconds));
    // Fixed-rate simulation: sleep to the next step unless it is already late.
    next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(dt));
    if (next > Clock::now()) std::this_thread::sleep_until(next);
    else next = Clock::now();
  }
  loop_->stop();
  while (loop_->telemetry().pop(sample)) {
    if (on_sample) on_sample(sample);
  }
  if (progress) progress("haptic session (real time)", 1.0);
  report.haptic_ticks = static_cast<std::int64_t>(loop_->ticks());
  finish_report(report, timer, seconds_between(start, Clock::now()));
  return report;
}

}  // namespace hof::coupling
