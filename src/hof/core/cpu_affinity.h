#pragma once
/// @file
/// Which CPUs the threads of a real-time session run on.
///
/// On a machine with few cores the scheduler places a waking thread where it sees room, which
/// is often the core the simulation is computing on: the 1 kHz haptic thread and the thread
/// that makes the surface snapshots then preempt the simulation a few hundred times a second
/// (and take its cache), while the other core idles. Real-time systems keep such threads
/// apart (Linux `isolcpus`, a PREEMPT_RT setup's affinity masks); HoF does it for its own
/// threads: the last CPU the process may use carries the haptic loop and the snapshots, the
/// others the simulation.
#include <span>
#include <string>
#include <vector>

namespace hof {

/// The CPUs this process may run on (its affinity mask, as `taskset` or a container set it),
/// in increasing order; empty when the system does not say.
[[nodiscard]] std::vector<int> allowed_cpus();

/// Restricts the calling thread to `cpus`; false when `cpus` is empty or the system refused.
bool pin_current_thread(std::span<const int> cpus);

/// How a real-time session spreads its threads over the CPUs it may use.
struct CpuPlan {
  std::vector<int> simulation;  ///< the simulation's threads (empty: not pinned)
  int haptic{-1};               ///< the haptic loop and the snapshot publisher (-1: not pinned)

  [[nodiscard]] bool pinned() const { return haptic >= 0; }
  /// "simulation on CPU 0, haptics on CPU 1", or why nothing is pinned.
  [[nodiscard]] std::string describe() const;
};

/// The last of `cpus` for the haptic thread, the others for the simulation; nothing pinned
/// with fewer than two CPUs (the threads must then share the one).
[[nodiscard]] CpuPlan plan_cpus(std::span<const int> cpus);

}  // namespace hof
