#include "hof/haptics/haptic_loop.h"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <fmt/format.h>
#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hof/core/cpu_affinity.h"

namespace hof::haptics {

namespace {

double monotonic_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void sleep_until(double seconds) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(std::floor(seconds));
  ts.tv_nsec = static_cast<long>((seconds - std::floor(seconds)) * 1e9);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

constexpr double kSpinTail_s = 150e-6;

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

Vec3 Calibration::vector_to_device(const Vec3& v) const {
  // Forces go back to the device by the rotation part of the calibration: a scaling
  // calibration (a Falcon's workspace blown up 3×) must not scale the force.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(position.topLeftCorner<3, 3>(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
  return (u * svd.matrixV().transpose()).transpose() * v;
}

Expected<void> validate_effects(const ForceEffects& effects) {
  if (effects.springs.size() > kMaxEffectsEach || effects.viscosities.size() > kMaxEffectsEach ||
      effects.constants.size() > kMaxEffectsEach || effects.magnets.size() > kMaxEffectsEach ||
      effects.position_functions.size() > kMaxEffectsEach || effects.time_functions.size() > kMaxEffectsEach) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("force effects: at most {} of each kind", kMaxEffectsEach));
  }
  for (const SpringEffect& e : effects.springs) {
    if (!e.position_m.allFinite() || !(e.spring_constant_n_per_m >= 0.0) || !std::isfinite(e.spring_constant_n_per_m) ||
        !(e.start_distance_m >= 0.0) || !(e.escape_distance_m >= 0.0) || !(e.damping_n_s_per_m >= 0.0)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "SpringEffect: position must be finite, springConstant, "
                        "startDistance, escapeDistance and damping >= 0");
    }
  }
  for (const ViscosityEffect& e : effects.viscosities) {
    if (!(e.viscosity_pa_s >= 0.0) || !(e.radius_m >= 0.0) || !(e.damping_factor >= 0.0) ||
        !std::isfinite(e.viscosity_pa_s)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "ViscosityEffect: viscosity, radius and dampingFactor must be >= 0");
    }
  }
  for (const ConstantForceEffect& e : effects.constants) {
    if (!e.force_n.allFinite()) return make_error(ErrorCode::kInvalidArgument, "ForceField: force must be finite");
  }
  // The magnets' closest point is searched over every triangle in the tick: bounded.
  std::size_t magnet_triangles = 0;
  for (const MagneticGeometryEffect& e : effects.magnets) {
    if (!e.surface || !(e.spring_constant_n_per_m >= 0.0) || !std::isfinite(e.spring_constant_n_per_m) ||
        !(e.start_distance_m >= 0.0) || !(e.escape_distance_m >= 0.0)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "MagneticGeometryEffect: a surface, and springConstant, startDistance "
                        "and escapeDistance >= 0, are needed");
    }
    magnet_triangles += e.surface->triangles.size();
  }
  if (magnet_triangles > kMaxMagnetTriangles) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("MagneticGeometryEffect: {} triangles in all, at most {} (the "
                                  "closest point is searched over each in every haptic tick)",
                                  magnet_triangles, kMaxMagnetTriangles));
  }
  return {};
}

HapticLoop::HapticLoop(Device& device, TripleBuffer<SurfaceSnapshot>& surfaces, const HapticLoopConfig& config,
                       TripleBuffer<HapticSettings>* settings)
    : HapticLoop(device, std::span<TripleBuffer<SurfaceSnapshot>* const>(std::array{&surfaces}.data(), 1), config,
                 settings) {}

HapticLoop::HapticLoop(Device& device, std::span<TripleBuffer<SurfaceSnapshot>* const> layers,
                       const HapticLoopConfig& config, TripleBuffer<HapticSettings>* settings)
    : layers_(layers.begin(),
              layers.begin() + static_cast<std::ptrdiff_t>(std::clamp<std::size_t>(layers.size(), 1, kMaxLayers))),
      config_(config),
      renderers_(layers_.size(), HapticRenderer(config.renderer, config.material, device.spec().max_stiffness_n_per_m)),
      have_surface_(layers_.size(), 0),
      stats_(1.0 / config.rate_hz),
      telemetry_(config.telemetry_capacity),
      contacts_(config.telemetry_capacity),
      settings_(settings),
      last_renderer_(config.renderer),
      max_force_n_(config.safety.max_force_n) {
  bindings_.push_back(
      std::make_unique<DeviceBinding>(DeviceBinding{&device, SafetyFilter(device.spec(), config_.safety)}));
  binding_.store(bindings_.back().get(), std::memory_order_release);
  // Room for changed effects, so that taking new settings in the tick never allocates.
  effects_.springs.reserve(kMaxEffectsEach);
  effects_.viscosities.reserve(kMaxEffectsEach);
  effects_.constants.reserve(kMaxEffectsEach);
  effects_.magnets.reserve(kMaxEffectsEach);
  effects_.position_functions.reserve(kMaxEffectsEach);
  effects_.time_functions.reserve(kMaxEffectsEach);
  apply_calibration(config_.calibration);
}

void HapticLoop::apply_calibration(const Calibration& calibration) {
  config_.calibration = calibration;
  // The rotation that takes world vectors to the device frame, computed once (not per tick);
  // fixed-size matrices: no allocation in the tick.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(config_.calibration.position.topLeftCorner<3, 3>(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
  world_to_device_ = (u * svd.matrixV().transpose()).transpose();
  const double world_scale = std::cbrt(std::abs(config_.calibration.position.topLeftCorner<3, 3>().determinant()));
  world_scale_ = world_scale > 0.0 && std::isfinite(world_scale) ? world_scale : 1.0;
  for (HapticRenderer& r : renderers_) r.set_world_scale(world_scale);
}

HapticLoop::~HapticLoop() { stop(); }

void HapticLoop::tick(double time_s) {
  const double nominal = 1.0 / config_.rate_hz;
  const double period = last_time_s_ < 0.0 ? nominal : time_s - last_time_s_;
  last_time_s_ = time_s;
  tick_impl(time_s, period, false);
}

void HapticLoop::take_settings() {
  if (!settings_ || !settings_->acquire()) return;
  const HapticSettings& s = settings_->read();
  if (!s.valid) {
    // The previous slot, which the materials pointed into, now belongs to the producer.
    for (HapticRenderer& r : renderers_) r.set_part_materials({});
    return;
  }
  // The renderer's configuration as the producer gave it (the renderer keeps a scaled copy).
  const bool renderer_changed = !(s.renderer == last_renderer_);
  if (renderer_changed) last_renderer_ = s.renderer;
  for (HapticRenderer& r : renderers_) {
    if (renderer_changed) r.reconfigure(s.renderer);
    r.set_part_materials(s.materials);
  }
  if (s.calibration.position != config_.calibration.position ||
      !s.calibration.orientation.coeffs().isApprox(config_.calibration.orientation.coeffs(), 0.0)) {
    apply_calibration(s.calibration);
    proxy_initialised_ = false;
  }
  if (s.max_force_n != max_force_n_) {
    max_force_n_ = s.max_force_n;
    binding_.load(std::memory_order_relaxed)->safety.set_max_force(max_force_n_);
  }
  // Copied into the capacity reserved at construction (the producer validated the counts, and
  // assign() within capacity does not allocate); a spring keeps its active state.
  const auto copy_within = [](auto& to, const auto& from) {
    to.assign(from.begin(), from.begin() + static_cast<std::ptrdiff_t>(std::min(from.size(), to.capacity())));
  };
  std::array<bool, kMaxEffectsEach> was_active{};
  for (std::size_t i = 0; i < effects_.springs.size(); ++i) was_active[i] = effects_.springs[i].active;
  copy_within(effects_.springs, s.effects.springs);
  for (std::size_t i = 0; i < effects_.springs.size(); ++i) effects_.springs[i].active = was_active[i];
  copy_within(effects_.viscosities, s.effects.viscosities);
  copy_within(effects_.constants, s.effects.constants);
  for (std::size_t i = 0; i < effects_.magnets.size(); ++i) was_active[i] = effects_.magnets[i].active;
  copy_within(effects_.magnets, s.effects.magnets);  // shared surfaces: a reference count, no allocation
  for (std::size_t i = 0; i < effects_.magnets.size(); ++i) effects_.magnets[i].active = was_active[i];
  copy_within(effects_.position_functions, s.effects.position_functions);
  copy_within(effects_.time_functions, s.effects.time_functions);
}

bool HapticLoop::switch_device(Device& device) {
  if (pending_.load(std::memory_order_acquire) != nullptr) return false;
  bindings_.push_back(
      std::make_unique<DeviceBinding>(DeviceBinding{&device, SafetyFilter(device.spec(), config_.safety)}));
  pending_.store(bindings_.back().get(), std::memory_order_release);
  return true;
}

// One function of ~165 lines on purpose: this is the haptic tick (1 kHz and more, never
// allocating, locking or waiting), and its stages — take the settings and a switched device,
// read and calibrate, render the layers, the tool and the effects, the safety filter, publish
// — share a dozen stack arrays (contacts, layer forces, surfaces) sized kMaxLayers. Split
// into functions they would pass those arrays by reference across calls the compiler may
// not inline, and the tick's cost is a measured cell (`hof bench --only haptic_rate`) that
// must not grow. The stages are marked by the comments below, in the order they run.
void HapticLoop::tick_impl(double time_s, double period_s, bool overrun) {
  const double dt = period_s > 0.0 && std::isfinite(period_s) ? period_s : 1.0 / config_.rate_hz;
  take_settings();
  if (DeviceBinding* next = pending_.exchange(nullptr, std::memory_order_acq_rel)) {
    // Another device: the old one is let go at zero force, the new one's filter keeps the
    // loop's counts, and the proxy starts again at its first reading.
    DeviceBinding* old = binding_.load(std::memory_order_relaxed);
    old->device->write_force(Vec3::Zero(), Vec3::Zero());
    next->safety.add_counters(old->safety.counters());
    next->safety.set_max_force(max_force_n_);
    for (HapticRenderer& r : renderers_) r.set_device_max_stiffness(next->device->spec().max_stiffness_n_per_m);
    proxy_initialised_ = false;
    binding_.store(next, std::memory_order_release);
  }
  DeviceBinding& bound = *binding_.load(std::memory_order_relaxed);
  Device& device = *bound.device;
  SafetyFilter& safety = bound.safety;
  std::array<bool, kMaxLayers> changed{};
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    changed[l] = layers_[l]->acquire();
    if (changed[l]) have_surface_[l] = 1;
  }

  // Read and calibrate.
  const DeviceReading reading = device.read(time_s);
  // A reading with any non-finite field (or a zero quaternion, which is no rotation at all) is
  // garbage as a whole: its position is not trusted either. A finite, non-unit quaternion is
  // only rounding or scale, and is normalised for the tool (its axis).
  const double orientation_norm = reading.orientation.coeffs().norm();
  const bool finite = reading.valid && reading.position_m.allFinite() && reading.velocity_m_per_s.allFinite() &&
                      std::isfinite(orientation_norm) && orientation_norm > 0.0;
  // A jump of metres in one tick (see SafetyConfig::max_reading_jump_m): far from the last
  // reading rendered and from the one before. Rendering it would drag the proxy across the
  // scene (sliding along every surface in the way) and back the next tick, with a force at the
  // device's limit in between. The history starts again with the proxy (a device switched, a
  // calibration changed).
  if (!proxy_initialised_) have_reading_history_ = false;
  bool jumped = false;
  if (finite) {
    const double limit = config_.safety.max_reading_jump_m;
    jumped = have_reading_history_ && limit > 0.0 && (reading.position_m - last_rendered_position_).norm() > limit &&
             (reading.position_m - last_reading_position_).norm() > limit;
    last_reading_position_ = reading.position_m;
    if (!jumped) last_rendered_position_ = reading.position_m;
    have_reading_history_ = true;
  }
  const bool valid = finite && !jumped;
  const Vec3 x = valid ? config_.calibration.to_world(reading.position_m) : Vec3::Zero();
  const Vec3 v = valid ? config_.calibration.vector_to_world(reading.velocity_m_per_s) : Vec3::Zero();
  if (valid && !proxy_initialised_) {
    for (HapticRenderer& r : renderers_) r.reset(x);
    if (tool_) tool_->restart();
    proxy_initialised_ = true;
  }

  // Render: each layer's surfaces with its own proxy (forces add up), then force effects.
  // The tool (a needle) comes between the surfaces and the effects: it may take over the
  // surface force of what it pierces.
  Vec3 requested = Vec3::Zero();
  std::array<ContactState, kMaxLayers> contacts{};
  std::array<Vec3, kMaxLayers> layer_forces{};
  layer_forces.fill(Vec3::Zero());
  Vec3 tool_force = Vec3::Zero();
  ToolState tool_state;
  std::size_t first_contact = kMaxLayers;
  if (valid && proxy_initialised_) {
    std::array<const SurfaceSnapshot*, kMaxLayers> surfaces{};
    for (std::size_t l = 0; l < layers_.size(); ++l) {
      const SurfaceSnapshot& surface = layers_[l]->read();
      if (have_surface_[l] && !surface.triangles.empty()) {
        contacts[l] = renderers_[l].update(x, v, surface, changed[l], dt);
        surfaces[l] = &surface;
      }
      layer_forces[l] = contacts[l].force;
      if (contacts[l].in_contact && first_contact == kMaxLayers) first_contact = l;
    }
    if (tool_) {
      ToolTickInput input;
      input.time_s = time_s;
      input.dt_s = dt;
      input.position = x;
      input.velocity = v;
      input.orientation =
          config_.calibration.orientation * Eigen::Quaterniond(reading.orientation.coeffs() / orientation_norm);
      input.contacts = std::span<const ContactState>(contacts.data(), layers_.size());
      input.surfaces = std::span<const SurfaceSnapshot* const>(surfaces.data(), layers_.size());
      input.max_stiffness_n_per_m = device.spec().max_stiffness_n_per_m / world_scale_;
      tool_force = tool_->tick(input, std::span<Vec3>(layer_forces.data(), layers_.size()), tool_state);
      tool_state.active = true;
    }
    for (std::size_t l = 0; l < layers_.size(); ++l) requested += layer_forces[l];
    requested += tool_force;
    requested += effects_.evaluate(x, v, time_s);
  } else if (tool_) {
    tool_state.active = true;  // mounted, without a reading: free
  }
  const std::size_t shown = first_contact < kMaxLayers ? first_contact : 0;
  const ContactState& contact = contacts[shown];

  // Safety, then out to the device (in its own frame). The geometry's age is the oldest
  // layer's (a layer of rigid shapes only never ages).
  double age = 0.0;
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    const SurfaceSnapshot& surface = layers_[l]->read();
    age = std::max(age, !have_surface_[l]   ? std::numeric_limits<double>::infinity()
                        : surface.is_static ? 0.0
                                            : time_s - surface.time_s);
  }
  // A failed simulation's last geometry counts as stale now (set_simulation_failed).
  if (simulation_failed_.load(std::memory_order_acquire)) age = std::numeric_limits<double>::infinity();
  const SafetyFilter::Reading reading_state = !reading.valid ? SafetyFilter::Reading::kMissing
                                              : valid        ? SafetyFilter::Reading::kValid
                                                             : SafetyFilter::Reading::kNonFinite;
  const Vec3 sent = safety.filter(requested, reading_state, age, overrun, dt);
  device.write_force(world_to_device_ * sent, Vec3::Zero());

  // Publish.
  const std::uint64_t tick = ticks_.fetch_add(1, std::memory_order_relaxed);
  HapticSample& out = samples_.write_slot();
  out.tick = tick;
  out.time_s = time_s;
  out.device = x;
  out.device_velocity = v;
  out.proxy = proxy_initialised_ ? renderers_[shown].contact().proxy : x;
  out.force = sent;
  out.requested_force = requested;
  out.contact = contact.in_contact;
  out.layer = static_cast<std::int32_t>(shown);
  out.triangle = contact.triangle;
  out.barycentric = contact.barycentric;
  out.contact_point = contact.point;
  out.contact_normal = contact.normal;
  out.penetration_m = contact.penetration_m;
  out.snapshot_sequence = have_surface_[shown] ? layers_[shown]->read().sequence : 0;
  out.period_s = period_s;
  out.buttons = reading.buttons;
  out.valid = valid;
  out.tool = tool_state;
  telemetry_.push(out);
  HapticContact c;
  c.tick = tick;
  c.time_s = time_s;
  c.valid = valid;
  c.force = sent;
  c.clamped = requested.norm() > device.spec().max_force_n;
  c.layer_count = static_cast<std::uint8_t>(layers_.size());
  // Each layer's share of what was sent (the safety layer scales the whole request).
  const double requested_norm = requested.norm();
  const double scale = requested_norm > 0.0 ? sent.norm() / requested_norm : 0.0;
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    HapticContact::Layer& layer = c.layers[l];
    layer.proxy = proxy_initialised_ ? renderers_[l].contact().proxy : x;
    layer.contact = contacts[l].in_contact;
    layer.triangle = contacts[l].triangle;
    layer.barycentric = contacts[l].barycentric;
    layer.force = scale * layer_forces[l];
    // What the contact pushes the tissue with (the renderer's, equal to the force felt except
    // with the FEM reaction); with a tool, the layer's share as the tool left it.
    layer.load = tool_ ? layer.force : scale * contacts[l].coupling_force;
  }
  c.tool = tool_state;
  c.tool.force = scale * tool_force;
  contacts_.push(c);
  samples_.publish();
  if (tick > 0) stats_.record(period_s, overrun);
}

void HapticLoop::start() {
  if (running_.load()) return;
  stop_requested_.store(false);
  running_.store(true, std::memory_order_release);
  // The clock starts at the call, not when the thread first runs (which a loaded machine may
  // delay): a caller that starts its own clock just before (the session's simulation, whose
  // snapshots carry its time) then shares this origin, and snapshot ages are not read short.
  origin_s_ = monotonic_seconds();
  last_start_s_ = next_due_s_ = origin_s_;
  first_realtime_tick_ = true;
  // A device with a servo loop of its own (OpenHaptics' scheduler) is the clock: one tick per
  // servo frame, on its thread.
  Device* device = binding_.load(std::memory_order_acquire)->device;
  if (device->start_servo(&HapticLoop::servo_tick, this)) {
    servo_device_ = device;
    scheduling_.store(static_cast<int>(Scheduling::device_servo), std::memory_order_release);
    return;
  }
  thread_ = std::thread([this] { run_thread(); });
}

void HapticLoop::stop() {
  stop_requested_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  if (servo_device_) {
    servo_device_->stop_servo();  // returns after its last call
    servo_device_ = nullptr;
  }
  running_.store(false, std::memory_order_release);
  binding_.load()->device->write_force(Vec3::Zero(), Vec3::Zero());
}

void HapticLoop::run_thread() {
  if (config_.cpu >= 0) {
    const std::array<int, 1> cpu{config_.cpu};
    pinned_.store(pin_current_thread(cpu), std::memory_order_release);
  }
  if (config_.realtime_priority) {
    // A 1 kHz loop must not wait behind the simulation; ask for real-time scheduling and
    // carry on without it where that is not permitted.
    sched_param param{};
    param.sched_priority = std::min(80, sched_get_priority_max(SCHED_FIFO));
    const bool granted = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
    scheduling_.store(static_cast<int>(granted ? Scheduling::realtime : Scheduling::refused),
                      std::memory_order_release);
  } else {
    scheduling_.store(static_cast<int>(Scheduling::not_requested), std::memory_order_release);
  }
  while (!stop_requested_.load(std::memory_order_acquire)) {
    realtime_tick();
    // Sleep, then spin the last stretch: a sleeping thread wakes up to ~100 µs late on a
    // loaded machine (the window and the simulation share the cores), which would spread the
    // period; the spin costs a sixth of a core (as HAPI's and CHAI3D's busy haptic loops, less).
    sleep_until(next_due_s_ - kSpinTail_s);
    while (monotonic_seconds() < next_due_s_ && !stop_requested_.load(std::memory_order_relaxed)) cpu_relax();
  }
  running_.store(false, std::memory_order_release);
}

void HapticLoop::realtime_tick() {
  const double period = 1.0 / config_.rate_hz;
  const double now = monotonic_seconds();
  const double measured = first_realtime_tick_ ? period : now - last_start_s_;
  const bool overrun = !first_realtime_tick_ && now > next_due_s_ + period;  // started a whole period late
  last_start_s_ = now;
  first_realtime_tick_ = false;
  tick_impl(now - origin_s_, measured, overrun);
  next_due_s_ += period;
  if (next_due_s_ < now) next_due_s_ = now;  // after a stall, do not try to catch up in a burst
}

}  // namespace hof::haptics
