#include "hof/core/cpu_affinity.h"

#include <gtest/gtest.h>

#include <array>
#include <thread>

namespace hof {
namespace {

TEST(CpuPlan, TheLastCpuCarriesTheHapticLoopAndTheOthersTheSimulation) {
  const std::array<int, 2> two{0, 1};
  const CpuPlan pair = plan_cpus(two);
  ASSERT_TRUE(pair.pinned());
  EXPECT_EQ(pair.haptic, 1);
  EXPECT_EQ(pair.simulation, std::vector<int>{0});
  EXPECT_EQ(pair.describe(), "simulation on CPU 0, haptics on CPU 1");

  // A process held to some CPUs (taskset, a container's cpuset): only those.
  const std::array<int, 3> some{2, 5, 7};
  const CpuPlan three = plan_cpus(some);
  EXPECT_EQ(three.haptic, 7);
  EXPECT_EQ(three.simulation, (std::vector<int>{2, 5}));
  EXPECT_EQ(three.describe(), "simulation on CPUs 2,5, haptics on CPU 7");
}

TEST(CpuPlan, OneCpuOrNoneIsNotPinned) {
  const std::array<int, 1> one{3};
  EXPECT_FALSE(plan_cpus(one).pinned());
  EXPECT_TRUE(plan_cpus(one).simulation.empty());
  EXPECT_FALSE(plan_cpus({}).pinned());
  EXPECT_EQ(plan_cpus({}).describe(), "not pinned");
}

TEST(CpuAffinity, AThreadIsPinnedToCpusTheProcessMayUseAndRefusedOthers) {
  const std::vector<int> cpus = allowed_cpus();
  ASSERT_FALSE(cpus.empty()) << "Linux reports the process's CPUs";
  bool pinned = false, refused_empty = true, refused_negative = true;
  std::vector<int> after;
  std::thread([&] {
    const std::array<int, 1> first{cpus.front()};
    pinned = pin_current_thread(first);
    refused_empty = !pin_current_thread({});
    const std::array<int, 1> negative{-1};
    refused_negative = !pin_current_thread(negative);
  }).join();
  EXPECT_TRUE(pinned);
  EXPECT_TRUE(refused_empty);
  EXPECT_TRUE(refused_negative);
  // Another thread's pinning leaves this one (and the process's mask) as it was.
  EXPECT_EQ(allowed_cpus(), cpus);
}

}  // namespace
}  // namespace hof
