#include "hof/core/error.h"

namespace hof {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::kIo:
      return "I/O error";
    case ErrorCode::kParse:
      return "parse error";
    case ErrorCode::kInvalidMesh:
      return "invalid mesh";
    case ErrorCode::kInvalidArgument:
      return "invalid argument";
    case ErrorCode::kMeshing:
      return "meshing failed";
    case ErrorCode::kUnsupported:
      return "unsupported";
  }
  return "error";
}

std::string Error::to_string() const {
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) {
      out += ':' + std::to_string(line);
    } else if (byte_offset >= 0) {
      out += ": byte " + std::to_string(byte_offset);
    }
    out += ": ";
  }
  out += message;
  return out;
}

}  // namespace hof
