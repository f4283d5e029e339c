#include "hof/core/assert.h"

#include <cstdio>
#include <cstdlib>

namespace hof::detail {

void assertion_failed(const char* condition, const char* message, std::source_location where) noexcept {
  // fprintf to stderr (unbuffered) writes without allocating: safe from the haptic thread.
  if (message != nullptr && message[0] != '\0') {
    std::fprintf(stderr, "%s:%u: assertion failed: %s (%s)\n", where.file_name(), static_cast<unsigned>(where.line()),
                 condition, message);
  } else {
    std::fprintf(stderr, "%s:%u: assertion failed: %s\n", where.file_name(), static_cast<unsigned>(where.line()),
                 condition);
  }
  std::abort();
}

}  // namespace hof::detail
