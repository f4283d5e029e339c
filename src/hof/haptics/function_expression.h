#pragma once
/// @file
/// A function of up to three variables given as text, as H3D's GeneralFunction gives it
/// ("10*y", "sin(2*t)"): compiled once to a fixed-size program, evaluated in the haptic tick
/// without allocation. Grammar (the common part of H3D's function parser): numbers, the named
/// variables, + − * / ^ (power, right-associative), unary −, parentheses, and the functions
/// sin cos tan asin acos atan exp log sqrt abs floor ceil, min(a, b), max(a, b), atan2(y, x),
/// pow(a, b); and the constant pi.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "hof/core/error.h"

namespace hof::haptics {

class FunctionExpression {
 public:
  static constexpr std::size_t kMaxOps = 96;
  static constexpr std::size_t kMaxVariables = 3;

  /// Compiles `text` over `variables` (at most three names, in the order evaluate() takes
  /// them). Errors (kParse): a syntax error, an unknown name, a program longer than kMaxOps.
  [[nodiscard]] static Expected<FunctionExpression> make(std::string_view text, std::span<const std::string> variables);

  /// The value at `values` (one per variable). Real-time safe.
  [[nodiscard]] double evaluate(std::span<const double> values) const;

  enum class OpCode : std::uint8_t {
    kConst,
    kVar,
    kAdd,
    kSub,
    kMul,
    kDiv,
    kPow,
    kNeg,
    kSin,
    kCos,
    kTan,
    kAsin,
    kAcos,
    kAtan,
    kExp,
    kLog,
    kSqrt,
    kAbs,
    kFloor,
    kCeil,
    kMin,
    kMax,
    kAtan2
  };
  struct Op {
    OpCode code{OpCode::kConst};
    std::uint8_t variable{0};
    double value{0.0};
  };

 private:
  std::array<Op, kMaxOps> ops_{};
  std::size_t size_{0};  // trivially copyable: copied into the haptic loop without allocating
};

}  // namespace hof::haptics
