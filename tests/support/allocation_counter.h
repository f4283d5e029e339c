#pragma once
// Counts heap allocations by replacing the global operator new/delete (Drake's limit_malloc
// idea): include in exactly one source file of a test program, then compare
// hof::testing::allocation_count() before and after the code that must not allocate.

#include <atomic>
#include <cstdlib>
#include <new>

// GCC cannot see that the replaced operator new allocates with malloc.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

// Clang's ThreadSanitizer runtime replaces operator new and delete itself (all in one object, so
// ours cannot replace some of them): there, nothing is counted and the tests that count skip
// (HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS). Every other build counts.
#define HOF_ALLOCATION_COUNTING 1
#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#undef HOF_ALLOCATION_COUNTING
#endif
#endif
#define HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS()                                                                    \
  do {                                                                                                            \
    if (!hof::testing::kCountingAllocations) GTEST_SKIP() << "allocations are not counted under ThreadSanitizer"; \
  } while (false)

namespace hof::testing {
#ifdef HOF_ALLOCATION_COUNTING
inline constexpr bool kCountingAllocations = true;
#else
inline constexpr bool kCountingAllocations = false;
#endif
inline std::atomic<long> g_allocation_count{0};
inline thread_local long t_allocation_count = 0;
/// Allocations (operator new calls) so far in this program.
inline long allocation_count() { return g_allocation_count.load(std::memory_order_relaxed); }
/// Allocations so far on the calling thread (others, e.g. a device's receiver, not counted).
inline long thread_allocation_count() { return t_allocation_count; }
}  // namespace hof::testing

#ifdef HOF_ALLOCATION_COUNTING
void* operator new(std::size_t size) {
  hof::testing::g_allocation_count.fetch_add(1, std::memory_order_relaxed);
  ++hof::testing::t_allocation_count;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, std::align_val_t align) {
  hof::testing::g_allocation_count.fetch_add(1, std::memory_order_relaxed);
  ++hof::testing::t_allocation_count;
  const auto a = static_cast<std::size_t>(align);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#endif  // HOF_ALLOCATION_COUNTING
