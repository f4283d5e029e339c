#include "hof/core/cpu_affinity.h"

#include <pthread.h>
#include <sched.h>

namespace hof {

std::vector<int> allowed_cpus() {
  std::vector<int> cpus;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  }
  return cpus;
}

bool pin_current_thread(std::span<const int> cpus) {
  if (cpus.empty()) return false;
  cpu_set_t set;
  CPU_ZERO(&set);
  for (const int cpu : cpus) {
    if (cpu < 0 || cpu >= CPU_SETSIZE) return false;
    CPU_SET(cpu, &set);
  }
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

std::string CpuPlan::describe() const {
  if (!pinned()) return "not pinned";
  std::string text = simulation.size() > 1 ? "simulation on CPUs " : "simulation on CPU ";
  for (std::size_t i = 0; i < simulation.size(); ++i) text += (i > 0 ? "," : "") + std::to_string(simulation[i]);
  return text + ", haptics on CPU " + std::to_string(haptic);
}

CpuPlan plan_cpus(std::span<const int> cpus) {
  CpuPlan plan;
  if (cpus.size() < 2) return plan;
  plan.haptic = cpus.back();
  plan.simulation.assign(cpus.begin(), cpus.end() - 1);
  return plan;
}

}  // namespace hof
