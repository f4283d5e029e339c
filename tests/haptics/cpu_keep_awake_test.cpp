#include "hof/haptics/cpu_keep_awake.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <string>
#include <thread>

#include "hof/core/cpu_affinity.h"

namespace hof::haptics {
namespace {

TEST(CpuKeepAwake, OnStartsOneIdleClassSpinnerPerCpuAndStopsThemAll) {
  // One per CPU the process may use (taskset, a container's CPU set), each held to its CPU.
  const std::size_t allowed = allowed_cpus().size();
  const auto cpus = static_cast<unsigned>(allowed > 0 ? allowed : std::max(1u, std::thread::hardware_concurrency()));
  {
    const CpuKeepAwake awake(KeepAwake::on);
    // SCHED_IDLE needs no privilege: every spinner must have taken it, none spins at normal
    // priority.
    EXPECT_EQ(awake.spinners(), static_cast<int>(cpus));
    EXPECT_EQ(std::string(awake.reason()), "on (asked)");
    // A thread of ordinary priority still runs to completion while they spin.
    std::atomic<long> work{0};
    std::thread worker([&] {
      for (long i = 0; i < 2'000'000; ++i) work.fetch_add(1, std::memory_order_relaxed);
    });
    worker.join();
    EXPECT_EQ(work.load(), 2'000'000);
  }  // the destructor joins every spinner: a hang here fails the test by its timeout
}

TEST(CpuKeepAwake, OffStartsNothing) {
  const CpuKeepAwake awake(KeepAwake::off);
  EXPECT_EQ(awake.spinners(), 0);
  EXPECT_EQ(std::string(awake.reason()), "off (asked)");
}

TEST(CpuKeepAwake, AutomaticFollowsTheHypervisorFlag) {
  const CpuKeepAwake awake(KeepAwake::automatic);
  if (running_under_hypervisor()) {
    EXPECT_GT(awake.spinners(), 0);
    EXPECT_EQ(std::string(awake.reason()), "on (virtual machine)");
  } else {
    EXPECT_EQ(awake.spinners(), 0);
    EXPECT_EQ(std::string(awake.reason()), "off (not a virtual machine)");
  }
}

}  // namespace
}  // namespace hof::haptics
