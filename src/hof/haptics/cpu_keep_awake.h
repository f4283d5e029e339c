#pragma once
/// @file
/// Keeps every CPU of a virtual machine from halting while the haptic loop runs.
///
/// The haptic thread sleeps most of each millisecond. On a virtual machine a CPU with nothing
/// to run executes HLT, the hypervisor takes the virtual CPU off its host core, and the timer
/// that should wake the haptic thread waits until the host gives the core back. On the
/// 2-vCPU development VM (docs/reliability.md) a SCHED_FIFO thread sleeping 1 ms
/// (`cyclictest -m -p 80 -i 1000`) woke up to 29 ms late, 64 times over 2 ms in 20 s, when the
/// machine was otherwise idle, and never over 2 ms while two ordinary threads kept both CPUs
/// busy. A kernel booted with `idle=poll` does the same for the whole machine; a guest cannot
/// change its boot line, so HoF runs one SCHED_IDLE spinner per CPU instead: the lowest
/// scheduling class, which yields at once to every other thread (the simulation, the window,
/// the haptic loop), so it takes no time from them, only keeps the CPU from halting. It costs
/// host CPU (and battery on a laptop), so it is on only where it helps: a hypervisor, or when
/// asked for.

#include <atomic>
#include <thread>
#include <vector>

namespace hof::haptics {

enum class KeepAwake { automatic, on, off };

/// Whether the CPU reports that it runs under a hypervisor (the `hypervisor` flag of
/// /proc/cpuinfo).
[[nodiscard]] bool running_under_hypervisor();

class CpuKeepAwake {
 public:
  /// Starts one spinner per online CPU when `mode` is on, or automatic under a hypervisor.
  explicit CpuKeepAwake(KeepAwake mode);
  ~CpuKeepAwake();
  CpuKeepAwake(const CpuKeepAwake&) = delete;
  CpuKeepAwake& operator=(const CpuKeepAwake&) = delete;

  /// Spinners running at SCHED_IDLE (0 when off, or when the system refused the policy: a
  /// spinner at normal priority would take time from the simulation, so it does not spin).
  [[nodiscard]] int spinners() const { return running_.load(std::memory_order_acquire); }
  /// Why the spinners are on or off, for the report.
  [[nodiscard]] const char* reason() const { return reason_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<int> running_{0};
  std::atomic<int> settled_{0};
  const char* reason_;
  std::vector<std::thread> threads_;
};

}  // namespace hof::haptics
