#include "hof/coupling/detail/session_runner.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "hof/coupling/command_seam.h"
#include "hof/coupling/detail/snapshot_publisher.h"

namespace hof::coupling::detail {

namespace {

// Real time: how far the simulation may fall behind the clock and still catch up (steps
// without sleeping until it is back); farther behind, it gives the time up and goes on from
// now. A step's cost varies by a tenth from step to step: without catching up, every step
// slower than dt would be lost for good while a faster one waits, and the simulation would
// keep real time only if its slowest steps did.
constexpr double kMaxCatchUp_s = 0.02;

// What a failed device says, or a plain reason when it says nothing.
std::string failure_of(const haptics::Device& device) {
  const std::string why = device.failure();
  return why.empty() ? std::string("the device stopped working") : why;
}

// The first hand whose device has failed (null: none).
const haptics::Device* failed_device(World& w) {
  for (std::size_t h = 0; h < hand_count(w); ++h) {
    const haptics::Device& device = hand_loop(w, h).device();
    if (device.health() == haptics::DeviceHealth::kFailed) return &device;
  }
  return nullptr;
}

// The telemetry of the hands after the first: not logged (the telemetry file is the first
// hand's); drained so that its ring never holds stale rows.
void drain_other_telemetry(World& w) {
  haptics::HapticSample sample;
  for (auto& hand : w.more_hands) {
    while (hand->loop->telemetry().pop(sample)) {
    }
  }
}

}  // namespace

void SessionRunner::begin() {
  begin_run(world_);
  stop_requested_.store(false, std::memory_order_relaxed);
}

void SessionRunner::finish_report(SessionReport& report, const StateTimer& timer, double wall_s) const {
  report.wall_s = wall_s;
  report.simulated_s = world_.time_s;
  report.simulation_steps_per_s = wall_s > 0.0 ? static_cast<double>(report.simulation_steps) / wall_s : 0.0;
  report.rate_untouched = StateTimer::rate(timer.untouched, timer.untouched_s);
  report.rate_deforming = StateTimer::rate(timer.deforming, timer.deforming_s);
  report.rate_in_contact = StateTimer::rate(timer.contact, timer.contact_s);
  report.haptic_periods = world_.loop->period_stats();
  report.safety = world_.loop->safety_counters();
  report.hands = hand_reports(world_);
  report.bodies.clear();
  for (const BodyRuntime& r : world_.bodies) {
    BodyReport b = r.report;
    report.max_displacement_m = std::max(report.max_displacement_m, b.max_displacement_m);
    report.bodies.push_back(std::move(b));
  }
}

std::int64_t SessionRunner::fade_out(std::int64_t tick, double tick_period, const SampleSink& on_sample) {
  // As the haptic thread does in real time, the loop goes on ticking without the simulation
  // until the safety filter has faded the force to zero, so that the run leaves the device at
  // rest rather than holding the last force. The fade takes fade_out_s, then the slew limit
  // brings what is left to zero; the count bounds it should a device's spec make the force
  // never settle.
  // Every hand fades (the longest fade of them bounds the count).
  haptics::HapticLoop& loop = *world_.loop;
  std::int64_t fade_ticks = 0;
  for (std::size_t h = 0; h < hand_count(world_); ++h) {
    const haptics::SafetyConfig& safety =
        h == 0 ? world_.config.haptics.safety : world_.more_hands[h - 1]->config.haptics.safety;
    const haptics::DeviceSpec& spec = hand_loop(world_, h).device().spec();
    const double slew_s = spec.max_force_rate_n_per_s > 0.0 ? spec.max_force_n / spec.max_force_rate_n_per_s : 0.0;
    fade_ticks =
        std::max(fade_ticks, static_cast<std::int64_t>(std::ceil((safety.fade_out_s + slew_s) / tick_period)) + 2);
  }
  haptics::HapticSample sample;
  for (std::int64_t k = 0; k < fade_ticks; ++k, ++tick) {
    const double time_s = static_cast<double>(world_.virtual_ticks + tick) * tick_period;
    loop.tick(time_s);
    bool at_rest = false;
    while (loop.telemetry().pop(sample)) {
      at_rest = sample.force.isZero(0.0);
      if (on_sample) on_sample(sample);
    }
    for (auto& hand : world_.more_hands) {
      hand->loop->tick(time_s);
      bool hand_at_rest = false;
      while (hand->loop->telemetry().pop(sample)) hand_at_rest = sample.force.isZero(0.0);
      at_rest = at_rest && hand_at_rest;
    }
    if (at_rest) {
      ++tick;
      break;
    }
  }
  // Their contacts act on nothing (the bodies no longer step).
  haptics::HapticContact c;
  for (std::size_t h = 0; h < hand_count(world_); ++h) {
    while (hand_loop(world_, h).contacts().pop(c)) {
    }
  }
  return tick;
}

SessionReport SessionRunner::run_virtual(double seconds, const SampleSink& on_sample, const ProgressSink& progress) {
  SessionReport report;
  begin();
  haptics::HapticLoop& loop = *world_.loop;
  const double tick_period = 1.0 / world_.config.haptics.rate_hz;
  const auto start = Clock::now();
  StateTimer timer;
  haptics::HapticSample sample;
  std::int64_t tick = 0;
  const auto total_ticks = static_cast<std::int64_t>(std::ceil(seconds / tick_period - 1e-6));
  std::int64_t steps = 0;
  while (tick < total_ticks && !stop_requested_.load(std::memory_order_relaxed)) {
    // N haptic ticks per simulation step (dt may change through a command).
    const auto ticks_per_step = std::max<std::int64_t>(1, std::llround(world_.dt / tick_period));
    for (std::int64_t k = 0; k < ticks_per_step; ++k, ++tick) {
      // Every hand ticks at the same virtual time, the first first: lock-step, deterministic.
      const double time_s = static_cast<double>(world_.virtual_ticks + tick) * tick_period;
      loop.tick(time_s);
      while (loop.telemetry().pop(sample)) {
        if (on_sample) on_sample(sample);
      }
      for (auto& hand : world_.more_hands) hand->loop->tick(time_s);
      drain_other_telemetry(world_);
    }
    const bool stepped = step_world(world_, seam_, publisher_, report, timer,
                                    static_cast<double>(world_.virtual_ticks + tick) * tick_period);
    // A device that has failed (unplugged, its SDK in error) gives no reading: the force fades
    // as for a divergence, and the run ends, saying why.
    const haptics::Device* failed = failed_device(world_);
    const bool device_failed = failed != nullptr;
    if (device_failed && report.device_failure.empty()) report.device_failure = failure_of(*failed);
    if (!stepped || device_failed) {
      tick = fade_out(tick, tick_period, on_sample);
      break;
    }
    ++steps;
    if (progress && (steps % 16 == 0 || tick >= total_ticks)) {
      progress("haptic session (virtual time)",
               std::min(1.0, static_cast<double>(tick) / static_cast<double>(total_ticks)));
    }
  }
  report.haptic_ticks = tick;
  world_.virtual_ticks += tick;  // a next run goes on from here (the device's clock does not restart)
  finish_report(report, timer, seconds_between(start, Clock::now()));
  return report;
}

void SessionRunner::simulation_thread() {
  // (A body's steps on several threads: its workers are placed by the system.)
  if (cpu_plan_.pinned()) pin_current_thread(cpu_plan_.simulation);
  // Each body steps in its own arena of simulation_threads() (start_realtime set them); this
  // one runs several bodies' steps side by side.
  tbb::task_arena arena(simulation_threads());
  arena.execute([this] { simulation_loop(); });
}

int SessionRunner::simulation_threads() const {
  if (world_.config.simulation_threads > 0) return world_.config.simulation_threads;
  // Automatic: every core the process may use but one, which the haptic loop (and the
  // window) share.
  const std::size_t allowed = allowed_cpus().size();
  const std::size_t cores = allowed > 0 ? allowed : std::max(1u, std::thread::hardware_concurrency());
  return static_cast<int>(std::max<std::size_t>(1, cores - 1));
}

void SessionRunner::simulation_loop() {
  // Fixed-rate simulation on its own thread: sleep to the next step unless already late.
  auto next = Clock::now();
  while (!stop_sim_.load(std::memory_order_acquire)) {
    if (!step_world(world_, seam_, publisher_, rt_report_, *rt_timer_, seconds_between(rt_start_, Clock::now()))) break;
    next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(world_.dt));
    const auto now = Clock::now();
    if (!paced_.load(std::memory_order_relaxed)) {
      next = now;
      std::this_thread::yield();
    } else if (next > now) {
      std::this_thread::sleep_until(next);
    } else if (seconds_between(next, now) > kMaxCatchUp_s) {
      next = now;  // too far behind to catch up (kMaxCatchUp_s)
    }
  }
  sim_finished_.store(true, std::memory_order_release);
}

void SessionRunner::start_realtime() {
  if (sim_thread_.joinable()) return;
  SessionReport fresh;
  rt_report_ = std::move(fresh);
  begin();
  rt_timer_ = std::make_unique<StateTimer>();
  stop_sim_.store(false);
  sim_finished_.store(false);
  // The simulation's threads: every core but one by default. On 2 cores that is one, and the
  // step then never wakes TBB's workers, which spin in sched_yield between a step's many short
  // loops and so took time from the haptic thread's core and delayed its wake-ups (the medium
  // liver at dt 1 ms, 2-core VM: haptic max period 5–10 ms with 2 threads, under 2 ms with 1;
  // the simulation's rate the same).
  world_.step_threads = simulation_threads();
  rt_report_.simulation_threads = world_.step_threads;
  for (BodyRuntime& r : world_.bodies) {
    fit_threads(world_, r);
    // What the bodies' steps will really run on (a model with threads of its own keeps them).
    if (r.body.deformable()) rt_report_.simulation_threads = mechanics::thread_count(r.state);
  }
  rt_start_ = Clock::now();
  cpu_plan_ = world_.config.pin_threads ? plan_cpus(allowed_cpus()) : CpuPlan{};
  rt_report_.cpu_placement = world_.config.pin_threads ? cpu_plan_.describe() : "not pinned (asked)";
  world_.loop->set_cpu(cpu_plan_.haptic);
  publisher_.start(cpu_plan_.pinned() ? cpu_plan_.haptic : -1);
  world_.loop->start();
  // Every other hand on a thread of its own, beside the first on the haptic CPU (rather than
  // one thread ticking every hand in turn, as CHAI3D does): a device with a servo loop of its
  // own (OpenHaptics, Device::start_servo) calls its ticks on its clock, so two such devices
  // cannot share one thread; and a hand whose device is slow to answer (a UDP bridge waiting,
  // an SDK read) then delays only its own ticks, never the other hand's. A tick takes tens of
  // microseconds of each millisecond: two fit on one CPU.
  for (auto& hand : world_.more_hands) {
    hand->loop->set_cpu(cpu_plan_.haptic);
    hand->loop->start();
  }
  sim_thread_ = std::thread([this] { simulation_thread(); });
}

void SessionRunner::poll(const SampleSink& on_sample) {
  haptics::HapticSample sample;
  while (world_.loop->telemetry().pop(sample)) {
    if (on_sample) on_sample(sample);
  }
  drain_other_telemetry(world_);
}

SessionReport SessionRunner::stop_realtime(const SampleSink& on_sample) {
  if (!sim_thread_.joinable()) return rt_report_;
  stop_sim_.store(true, std::memory_order_release);
  sim_thread_.join();
  publisher_.stop();
  world_.loop->stop();
  for (auto& hand : world_.more_hands) hand->loop->stop();
  poll(on_sample);
  // Contacts of the ticks after the last step are not applied.
  haptics::HapticContact c;
  for (std::size_t h = 0; h < hand_count(world_); ++h) {
    while (hand_loop(world_, h).contacts().pop(c)) {
    }
  }
  rt_report_.haptic_ticks = static_cast<std::int64_t>(world_.loop->ticks());
  // Virtual-time runs step on the caller's thread with every core again.
  world_.step_threads = 0;
  for (BodyRuntime& r : world_.bodies) fit_threads(world_, r);
  finish_report(rt_report_, *rt_timer_, seconds_between(rt_start_, Clock::now()));
  return rt_report_;
}

SessionReport SessionRunner::run_realtime(double seconds, const SampleSink& on_sample, const ProgressSink& progress) {
  start_realtime();
  const auto start = Clock::now();
  std::int64_t polls = 0;
  std::optional<double> device_failed_at;
  std::string device_failure;
  for (;;) {
    const double elapsed = seconds_between(start, Clock::now());
    if (elapsed >= seconds || sim_finished_.load(std::memory_order_acquire) ||
        stop_requested_.load(std::memory_order_relaxed))
      break;
    // A device that has failed: the haptic loop fades its force out (it gives no reading);
    // once that has had its time, the run ends, saying why.
    if (const haptics::Device* failed = failed_device(world_)) {
      if (!device_failed_at) device_failed_at = elapsed;
      const haptics::SafetyConfig& safety = world_.config.haptics.safety;
      const haptics::DeviceSpec& spec = failed->spec();
      const double fade_s = safety.fade_out_s +
                            (spec.max_force_rate_n_per_s > 0.0 ? spec.max_force_n / spec.max_force_rate_n_per_s : 0.0);
      if (elapsed - *device_failed_at > fade_s + 0.01) {
        device_failure = failure_of(*failed);
        break;
      }
    }
    poll(on_sample);
    if (progress && ++polls % 16 == 0) progress("haptic session (real time)", std::min(1.0, elapsed / seconds));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  SessionReport report = stop_realtime(on_sample);
  report.device_failure = device_failure;
  if (progress) progress("haptic session (real time)", 1.0);
  return report;
}

}  // namespace hof::coupling::detail
