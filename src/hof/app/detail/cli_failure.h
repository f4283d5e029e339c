#pragma once
/// @file
/// How a `hof` subcommand ends on an error: the message on stderr, prefixed `hof:`, and exit
/// status 1.

#include <cstdio>
#include <string>

#include "hof/core/error.h"

namespace hof::app::detail {

inline int fail(const std::string& message) {
  std::fprintf(stderr, "hof: %s\n", message.c_str());
  return 1;
}

inline int fail(const Error& error) { return fail(error.to_string()); }

}  // namespace hof::app::detail
