#pragma once
/// @file
/// hof::Error and hof::Expected: how every failure caused by outside input (a file, an XML
/// attribute, a command-line value, a device) is reported. Nothing in core, mechanics or
/// haptics throws; functions that read the outside world return Expected<T>.

#include <cstdint>
#include <expected>
#include <string>

namespace hof {

/// What kind of failure an Error is. Callers branch on this, never on message text.
enum class ErrorCode : std::uint8_t {
  kIo,               ///< a file could not be opened, read or written
  kParse,            ///< the text or bytes of a file do not follow its format
  kInvalidMesh,      ///< the file parses but the mesh is unusable (index out of range, NaN, ...)
  kInvalidArgument,  ///< a parameter from the user is out of its valid range
  kMeshing,          ///< the tetrahedral mesher failed (open or self-intersecting surface, ...)
  kUnsupported,      ///< a valid input that this version does not handle
};

/// A failure with where it happened. `file` and `line` are filled when known (line is
/// 1-based; 0 means unknown); `byte_offset` is used instead of a line for binary files.
struct Error {
  ErrorCode code{ErrorCode::kParse};
  std::string message;
  std::string file;
  std::int64_t line{0};
  std::int64_t byte_offset{-1};

  /// One line for a user: "FILE:LINE: message" (or "FILE: byte N: message", or "message").
  [[nodiscard]] std::string to_string() const;
};

/// Result of an operation that can fail on outside input.
template <class T>
using Expected = std::expected<T, Error>;

/// Shorthand to build the error side of an Expected.
[[nodiscard]] inline std::unexpected<Error> make_error(ErrorCode code, std::string message, std::string file = {},
                                                       std::int64_t line = 0) {
  return std::unexpected<Error>(Error{code, std::move(message), std::move(file), line, -1});
}

/// Human-readable name of an error code ("parse error", "I/O error", ...).
[[nodiscard]] const char* to_string(ErrorCode code);

}  // namespace hof
