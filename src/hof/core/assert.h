#pragma once
/// @file
/// Assertions for internal invariants — what HoF's own code guarantees, never what a user's
/// input may break (bad input is an `hof::Error` with the file, line or component).
///
///  - `HOF_ASSERT(condition)`: checked where assertions are on (the debug and sanitizer
///    presets: `NDEBUG` not defined), compiled out of release builds, so it may sit in the
///    haptic tick and inner loops.
///  - `HOF_CHECK(condition, message)`: always checked, for invariants whose failure would
///    otherwise corrupt results silently and whose test is cheap beside the work it guards.
///
/// A failed assertion prints `file:line: assertion failed: condition (message)` on stderr and
/// aborts: a broken invariant is a bug to fix, not a state to run on. Printing uses no
/// allocation, so a failure in the haptic thread reports itself too.

#include <source_location>

namespace hof::detail {
[[noreturn]] void assertion_failed(const char* condition, const char* message, std::source_location where) noexcept;
}  // namespace hof::detail

#define HOF_CHECK(condition, message)                                                        \
  do {                                                                                       \
    if (!(condition)) [[unlikely]]                                                           \
      ::hof::detail::assertion_failed(#condition, message, std::source_location::current()); \
  } while (false)

#ifdef NDEBUG
// Not evaluated, but still compiled, so an assertion cannot rot in release builds.
#define HOF_ASSERT(condition)                \
  do {                                       \
    if (false) static_cast<void>(condition); \
  } while (false)
#else
#define HOF_ASSERT(condition) HOF_CHECK(condition, "")
#endif
