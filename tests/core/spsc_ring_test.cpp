// The bounded lock-free queue of telemetry and commands (src/hof/core/spsc_ring.h): first in
// first out across many wrap-arounds, capacity a power of two, a full ring dropping the newest
// record and counting it, and between two threads every record arriving once and in order
// (run under ThreadSanitizer by scripts/test.sh).

#include "hof/core/spsc_ring.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace hof {
namespace {

TEST(SpscRing, CapacityIsRoundedUpToAPowerOfTwo) {
  EXPECT_EQ(SpscRing<int>(0).capacity(), 2u);
  EXPECT_EQ(SpscRing<int>(2).capacity(), 2u);
  EXPECT_EQ(SpscRing<int>(3).capacity(), 4u);
  EXPECT_EQ(SpscRing<int>(1000).capacity(), 1024u);
  EXPECT_EQ(SpscRing<int>(1024).capacity(), 1024u);
}

TEST(SpscRing, FirstInFirstOutAcrossWrapArounds) {
  SpscRing<int> ring(4);
  int value = -1;
  EXPECT_FALSE(ring.pop(value));
  EXPECT_EQ(value, -1);  // untouched when empty
  int next_in = 0, next_out = 0;
  for (int round = 0; round < 100; ++round) {
    for (int k = 0; k < 1 + round % 4; ++k) ASSERT_TRUE(ring.push(next_in++));
    while (ring.pop(value)) ASSERT_EQ(value, next_out++);
  }
  EXPECT_EQ(next_out, next_in);
  EXPECT_EQ(ring.dropped(), 0u);
}

TEST(SpscRing, AFullRingDropsTheNewestAndCountsIt) {
  SpscRing<int> ring(4);
  for (int k = 0; k < 4; ++k) ASSERT_TRUE(ring.push(k));
  EXPECT_FALSE(ring.push(4));
  EXPECT_FALSE(ring.push(5));
  EXPECT_EQ(ring.dropped(), 2u);
  int value = -1;
  for (int k = 0; k < 4; ++k) {
    ASSERT_TRUE(ring.pop(value));
    EXPECT_EQ(value, k);  // the oldest kept, the newest dropped
  }
  EXPECT_FALSE(ring.pop(value));
  EXPECT_TRUE(ring.push(6));  // room again
}

TEST(SpscRing, BetweenTwoThreadsEveryRecordArrivesOnceAndInOrder) {
  constexpr std::uint64_t kCount = 200000;
  SpscRing<std::uint64_t> ring(64);
  std::uint64_t pushed = 0;
  std::thread producer([&] {
    for (std::uint64_t k = 1; k <= kCount; ++k) {
      if (ring.push(k)) ++pushed;
    }
  });
  std::uint64_t last = 0, popped = 0, disorder = 0;
  std::uint64_t value = 0;
  for (;;) {
    if (ring.pop(value)) {
      ++popped;
      if (value <= last) ++disorder;
      last = value;
      continue;
    }
    if (popped + ring.dropped() == kCount) break;  // the producer is done and the ring empty
    std::this_thread::yield();
  }
  producer.join();
  EXPECT_EQ(disorder, 0u);
  EXPECT_EQ(popped, pushed);
  EXPECT_EQ(popped + ring.dropped(), kCount);
}

}  // namespace
}  // namespace hof
