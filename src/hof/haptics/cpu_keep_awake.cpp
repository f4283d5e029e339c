#include "hof/haptics/cpu_keep_awake.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <string>

#include "hof/core/cpu_affinity.h"

namespace hof::haptics {

bool running_under_hypervisor() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.starts_with("flags") && (line.find(" hypervisor ") != std::string::npos || line.ends_with(" hypervisor")))
      return true;
  }
  return false;
}

CpuKeepAwake::CpuKeepAwake(KeepAwake mode) {
  const bool wanted = mode == KeepAwake::on || (mode == KeepAwake::automatic && running_under_hypervisor());
  if (!wanted) {
    reason_ = mode == KeepAwake::off ? "off (asked)" : "off (not a virtual machine)";
    return;
  }
  reason_ = mode == KeepAwake::on ? "on (asked)" : "on (virtual machine)";
  // One spinner on each CPU the process may use (left to themselves, two could share one CPU
  // and leave another to halt).
  std::vector<int> allowed = allowed_cpus();
  const auto cpus =
      static_cast<unsigned>(allowed.empty() ? std::max(1u, std::thread::hardware_concurrency()) : allowed.size());
  threads_.reserve(cpus);
  for (unsigned i = 0; i < cpus; ++i) {
    const int cpu = allowed.empty() ? -1 : allowed[i];
    threads_.emplace_back([this, cpu] {
      if (cpu >= 0) pin_current_thread(std::array<int, 1>{cpu});
      sched_param param{};
      param.sched_priority = 0;
      const bool idle = pthread_setschedparam(pthread_self(), SCHED_IDLE, &param) == 0;
      if (idle) running_.fetch_add(1, std::memory_order_acq_rel);
      settled_.fetch_add(1, std::memory_order_acq_rel);
      if (!idle) return;
      while (!stop_.load(std::memory_order_relaxed)) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
      }
    });
  }
  // The count the report gives is final once every spinner has chosen.
  while (settled_.load(std::memory_order_acquire) < static_cast<int>(cpus)) std::this_thread::yield();
  if (spinners() == 0) reason_ = "off (SCHED_IDLE refused)";
}

CpuKeepAwake::~CpuKeepAwake() {
  stop_.store(true, std::memory_order_relaxed);
  for (std::thread& t : threads_) t.join();
}

}  // namespace hof::haptics
