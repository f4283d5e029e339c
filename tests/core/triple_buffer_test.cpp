// The triple buffer the loops hand snapshots through (src/hof/core/triple_buffer.h): the
// consumer sees the latest published value, each once, never a torn one while the producer
// writes on (run under ThreadSanitizer by scripts/test.sh).

#include "hof/core/triple_buffer.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

namespace hof {
namespace {

TEST(TripleBuffer, TheConsumerTakesTheLatestPublishedValueOnce) {
  TripleBuffer<int> buffer(7);
  EXPECT_FALSE(buffer.acquire());  // nothing published yet
  EXPECT_EQ(buffer.read(), 7);     // every slot starts as the initial value
  buffer.write_slot() = 1;
  buffer.publish();
  buffer.write_slot() = 2;
  buffer.publish();
  buffer.write_slot() = 3;  // written, not published
  EXPECT_TRUE(buffer.acquire());
  EXPECT_EQ(buffer.read(), 2);     // the latest published; 1 was overtaken
  EXPECT_FALSE(buffer.acquire());  // no newer value
  EXPECT_EQ(buffer.read(), 2);     // still readable
  buffer.publish();
  EXPECT_TRUE(buffer.acquire());
  EXPECT_EQ(buffer.read(), 3);
  EXPECT_EQ(buffer.published(), 3u);
}

TEST(TripleBuffer, TheProducerNeverWritesTheSlotBeingRead) {
  TripleBuffer<int> buffer(0);
  for (int k = 1; k <= 50; ++k) {
    buffer.write_slot() = k;
    buffer.publish();
    if (k % 3 == 0) {
      ASSERT_TRUE(buffer.acquire());
      const int* reading = &buffer.read();
      EXPECT_NE(&buffer.write_slot(), reading);
      EXPECT_EQ(*reading, k);
    }
  }
}

struct Stamped {
  std::uint64_t a{0};
  std::array<std::uint64_t, 64> payload{};
  std::uint64_t b{0};
};

TEST(TripleBuffer, ConsumerNeverSeesATornValue) {
  TripleBuffer<Stamped> buffer;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t k = 1; k < 200000; ++k) {
      Stamped& s = buffer.write_slot();
      s.a = k;
      s.payload.fill(k);
      s.b = k;
      buffer.publish();
    }
    done.store(true);
  });
  std::uint64_t last = 0, torn = 0, backwards = 0, reads = 0;
  for (;;) {
    const bool finished = done.load();
    if (!buffer.acquire()) {
      if (finished) break;
      continue;
    }
    const Stamped& s = buffer.read();
    ++reads;
    bool consistent = s.a == s.b;
    for (std::uint64_t v : s.payload) consistent = consistent && v == s.a;
    if (!consistent) ++torn;
    if (s.a < last) ++backwards;
    last = s.a;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_GT(reads, 0u);
}

}  // namespace
}  // namespace hof
