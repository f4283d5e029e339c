#pragma once
/// @file
/// Lock-free single-producer single-consumer triple buffer: the producer always has a slot to
/// write, the consumer always reads the latest complete value, neither ever waits. Used for
/// the snapshots the simulation, haptic and graphics loops hand to each other (SOFA's
/// LCPForceFeedback has the idea; here with atomics and no lock). The three slots are
/// constructed up front, so exchanging values never allocates.

#include <array>
#include <atomic>
#include <cstdint>
#include <utility>

namespace hof {

template <class T>
class TripleBuffer {
 public:
  /// All three slots start as copies of `initial` (sized once: later writes reuse storage).
  explicit TripleBuffer(const T& initial = T{}) : slots_{initial, initial, initial} {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // ---- producer side ----
  /// The slot to fill. Valid until publish().
  T& write_slot() { return slots_[back_]; }
  /// Makes the written slot the latest value.
  void publish() {
    // Swap the back slot with the middle one and mark it fresh.
    const std::uint32_t previous = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = previous & kIndexMask;
    ++published_;
  }

  // ---- consumer side ----
  /// Takes the latest published value if there is a newer one than last time; returns whether
  /// it changed. read() stays valid until the next acquire().
  bool acquire() {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return false;
    const std::uint32_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = previous & kIndexMask;
    return true;
  }
  [[nodiscard]] const T& read() const { return slots_[front_]; }
  [[nodiscard]] T& read_mutable() { return slots_[front_]; }

  /// Number of publish() calls (producer's count; for diagnostics on the producer thread).
  [[nodiscard]] std::uint64_t published() const { return published_; }

 private:
  static constexpr std::uint32_t kFresh = 4;
  static constexpr std::uint32_t kIndexMask = 3;
  std::array<T, 3> slots_;
  std::uint32_t back_{0};                 // producer-owned
  std::atomic<std::uint32_t> middle_{1};  // shared: index | kFresh
  std::uint32_t front_{2};                // consumer-owned
  std::uint64_t published_{0};
};

}  // namespace hof
