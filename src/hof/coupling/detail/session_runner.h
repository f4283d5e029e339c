#pragma once
/// @file
/// The two ways a session runs its world through step_world(): virtual time (the haptic ticks
/// and the steps in lock-step on the caller's thread, deterministic) and real time (the haptic
/// thread, the simulation thread and the snapshot publisher, a supervisor polling).

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <thread>

#include "hof/core/cpu_affinity.h"
#include "hof/core/progress.h"
#include "hof/coupling/detail/world_step.h"

namespace hof::coupling::detail {

using SampleSink = std::function<void(const haptics::HapticSample&)>;

class SessionRunner {
 public:
  SessionRunner(World& world, CommandSeam& seam, SnapshotPublisher& publisher)
      : world_(world), seam_(seam), publisher_(publisher) {}
  SessionRunner(const SessionRunner&) = delete;
  SessionRunner& operator=(const SessionRunner&) = delete;

  SessionReport run_virtual(double seconds, const SampleSink& on_sample, const ProgressSink& progress);
  SessionReport run_realtime(double seconds, const SampleSink& on_sample, const ProgressSink& progress);
  void start_realtime();
  void poll(const SampleSink& on_sample);
  SessionReport stop_realtime(const SampleSink& on_sample);

  [[nodiscard]] bool realtime_running() const { return sim_thread_.joinable(); }
  [[nodiscard]] bool simulation_ended() const {
    return sim_finished_.load(std::memory_order_acquire) && !stop_sim_.load();
  }
  void set_pacing(bool paced) { paced_.store(paced, std::memory_order_relaxed); }
  [[nodiscard]] bool pacing() const { return paced_.load(std::memory_order_relaxed); }
  void request_stop() { stop_requested_.store(true, std::memory_order_relaxed); }

 private:
  // Virtual time, after the simulation stopped or the device failed: ticks until the force is
  // faded to zero. Returns the ticks run.
  std::int64_t fade_out(std::int64_t tick, double tick_period, const SampleSink& on_sample);
  void begin();
  void finish_report(SessionReport& report, const StateTimer& timer, double wall_s) const;
  [[nodiscard]] int simulation_threads() const;
  void simulation_thread();
  void simulation_loop();

  World& world_;
  CommandSeam& seam_;
  SnapshotPublisher& publisher_;
  std::atomic<bool> stop_requested_{false};
  // Real time.
  std::thread sim_thread_;
  CpuPlan cpu_plan_;  // where the threads run
  std::atomic<bool> stop_sim_{false};
  std::atomic<bool> sim_finished_{false};
  std::atomic<bool> paced_{true};
  SessionReport rt_report_;
  std::unique_ptr<StateTimer> rt_timer_;
  std::chrono::steady_clock::time_point rt_start_;
};

}  // namespace hof::coupling::detail
