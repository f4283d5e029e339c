#pragma once
/// @file
/// Bounded lock-free single-producer single-consumer queue of fixed-size records (copying one
/// must not allocate: plain structs of numbers and fixed-size Eigen vectors),
/// sized once: the haptic thread pushes one telemetry record per tick without allocating or
/// locking; a logger thread drains it. A full ring drops the newest record and counts it, so
/// the real-time side never waits.

#include <atomic>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace hof {

template <class T>
class SpscRing {
  static_assert(std::is_copy_assignable_v<T> && std::is_default_constructible_v<T>);

 public:
  /// Capacity rounded up to a power of two.
  explicit SpscRing(std::size_t capacity) {
    std::size_t size = 2;
    while (size < capacity) size *= 2;
    slots_.resize(size);
    mask_ = size - 1;
  }

  /// Producer: false (and counted) when full.
  bool push(const T& value) {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) > mask_) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer: false when empty.
  bool pop(T& value) {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    value = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  [[nodiscard]] std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::size_t capacity() const { return mask_ + 1; }

 private:
  std::vector<T> slots_;
  std::size_t mask_{0};
  alignas(64) std::atomic<std::uint64_t> head_{0};
  alignas(64) std::atomic<std::uint64_t> tail_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace hof
