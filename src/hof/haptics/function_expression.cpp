// Recursive descent from text to a postfix program; evaluation runs the program on a fixed
// stack. The compiler tracks the stack depth, so evaluate() never overflows it. No exceptions
// (haptics never throws): the first error is recorded and the parse winds down.

#include "hof/haptics/function_expression.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <numbers>
#include <utility>

namespace hof::haptics {
namespace {

using Op = FunctionExpression::Op;
using OpCode = FunctionExpression::OpCode;

constexpr std::size_t kMaxStack = 32;

class Compiler {
 public:
  Compiler(std::string_view text, std::span<const std::string> variables) : text_(text), variables_(variables) {}

  std::size_t compile(std::array<Op, FunctionExpression::kMaxOps>& ops) {
    ops_ = &ops;
    expression();
    skip_space();
    if (i_ < text_.size()) error(fmt::format("unexpected '{}' at character {}", text_[i_], i_ + 1));
    return size_;
  }
  /// The first error ("" when the text compiled).
  [[nodiscard]] const std::string& failure() const { return failure_; }

 private:
  // Records the first error; parsing then winds down (every loop below consumes text).
  void error(std::string message) {
    if (failure_.empty()) failure_ = std::move(message);
  }
  void skip_space() {
    while (i_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[i_]))) ++i_;
  }
  bool accept(char c) {
    skip_space();
    if (i_ < text_.size() && text_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!accept(c)) return error(fmt::format("expected '{}' at character {}", c, i_ + 1));
  }
  // Appends an op; `pops` operands replaced by one result.
  void emit(OpCode code, int pops, double value = 0.0, std::uint8_t variable = 0) {
    if (!failure_.empty()) return;
    if (size_ >= FunctionExpression::kMaxOps)
      return error(fmt::format("longer than {} operations", FunctionExpression::kMaxOps));
    (*ops_)[size_++] = Op{code, variable, value};
    depth_ += 1 - pops;
    if (depth_ > static_cast<int>(kMaxStack)) return error("nested too deeply");
  }

  // expression := term (('+' | '-') term)*
  void expression() {
    term();
    for (;;) {
      if (accept('+')) {
        term();
        emit(OpCode::kAdd, 2);
      } else if (accept('-')) {
        term();
        emit(OpCode::kSub, 2);
      } else
        return;
    }
  }
  // term := unary (('*' | '/') unary)*
  void term() {
    unary();
    for (;;) {
      if (accept('*')) {
        unary();
        emit(OpCode::kMul, 2);
      } else if (accept('/')) {
        unary();
        emit(OpCode::kDiv, 2);
      } else
        return;
    }
  }
  // unary := '-' unary | '+' unary | power
  void unary() {
    if (accept('-')) {
      unary();
      emit(OpCode::kNeg, 1);
      return;
    }
    if (accept('+')) {
      unary();
      return;
    }
    power();
  }
  // power := primary ('^' unary)?   (right-associative: 2^3^2 = 2^9)
  void power() {
    primary();
    if (accept('^')) {
      unary();
      emit(OpCode::kPow, 2);
    }
  }
  void primary() {
    skip_space();
    if (i_ >= text_.size()) return error("unexpected end");
    const char c = text_[i_];
    if (accept('(')) {
      expression();
      expect(')');
      return;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(text_.data() + i_, text_.data() + text_.size(), v);
      if (ec != std::errc{}) return error(fmt::format("bad number at character {}", i_ + 1));
      i_ = static_cast<std::size_t>(ptr - text_.data());
      emit(OpCode::kConst, 0, v);
      return;
    }
    if (!std::isalpha(static_cast<unsigned char>(c)) && c != '_')
      return error(fmt::format("unexpected '{}' at character {}", c, i_ + 1));
    const std::size_t start = i_;
    while (i_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[i_])) || text_[i_] == '_')) ++i_;
    const std::string_view name = text_.substr(start, i_ - start);
    for (std::size_t k = 0; k < variables_.size(); ++k) {
      if (variables_[k] == name) {
        emit(OpCode::kVar, 0, 0.0, static_cast<std::uint8_t>(k));
        return;
      }
    }
    if (name == "pi") {
      emit(OpCode::kConst, 0, std::numbers::pi);
      return;
    }
    static constexpr std::pair<std::string_view, OpCode> kOne[] = {
        {"sin", OpCode::kSin},   {"cos", OpCode::kCos},   {"tan", OpCode::kTan},     {"asin", OpCode::kAsin},
        {"acos", OpCode::kAcos}, {"atan", OpCode::kAtan}, {"exp", OpCode::kExp},     {"log", OpCode::kLog},
        {"sqrt", OpCode::kSqrt}, {"abs", OpCode::kAbs},   {"floor", OpCode::kFloor}, {"ceil", OpCode::kCeil}};
    static constexpr std::pair<std::string_view, OpCode> kTwo[] = {
        {"min", OpCode::kMin}, {"max", OpCode::kMax}, {"atan2", OpCode::kAtan2}, {"pow", OpCode::kPow}};
    for (const auto& [fname, code] : kOne) {
      if (fname != name) continue;
      expect('(');
      expression();
      expect(')');
      emit(code, 1);
      return;
    }
    for (const auto& [fname, code] : kTwo) {
      if (fname != name) continue;
      expect('(');
      expression();
      expect(',');
      expression();
      expect(')');
      emit(code, 2);
      return;
    }
    std::string known;
    for (const std::string& v : variables_) known += fmt::format("{}{}", known.empty() ? "" : ", ", v);
    return error(fmt::format("unknown name '{}' (the variables are: {})", name, known.empty() ? "none" : known));
  }

  std::string_view text_;
  std::span<const std::string> variables_;
  std::array<Op, FunctionExpression::kMaxOps>* ops_{nullptr};
  std::size_t size_{0};
  std::size_t i_{0};
  int depth_{0};
  std::string failure_;
};

}  // namespace

Expected<FunctionExpression> FunctionExpression::make(std::string_view text, std::span<const std::string> variables) {
  if (variables.size() > kMaxVariables)
    return make_error(ErrorCode::kParse, fmt::format("at most {} variables, got {}", kMaxVariables, variables.size()));
  FunctionExpression f;
  Compiler compiler(text, variables);
  f.size_ = compiler.compile(f.ops_);
  if (!compiler.failure().empty())
    return make_error(ErrorCode::kParse, fmt::format("'{}': {}", text, compiler.failure()));
  return f;
}

double FunctionExpression::evaluate(std::span<const double> values) const {
  std::array<double, kMaxStack> stack{};
  std::size_t top = 0;  // number of values on the stack; the compiler bounded it by kMaxStack
  for (std::size_t k = 0; k < size_; ++k) {
    const Op& op = ops_[k];
    switch (op.code) {
      case OpCode::kConst:
        stack[top++] = op.value;
        continue;
      case OpCode::kVar:
        stack[top++] = op.variable < values.size() ? values[op.variable] : 0.0;
        continue;
      default:
        break;
    }
    double& a = stack[top - 1];
    switch (op.code) {
      case OpCode::kNeg:
        a = -a;
        continue;
      case OpCode::kSin:
        a = std::sin(a);
        continue;
      case OpCode::kCos:
        a = std::cos(a);
        continue;
      case OpCode::kTan:
        a = std::tan(a);
        continue;
      case OpCode::kAsin:
        a = std::asin(a);
        continue;
      case OpCode::kAcos:
        a = std::acos(a);
        continue;
      case OpCode::kAtan:
        a = std::atan(a);
        continue;
      case OpCode::kExp:
        a = std::exp(a);
        continue;
      case OpCode::kLog:
        a = std::log(a);
        continue;
      case OpCode::kSqrt:
        a = std::sqrt(a);
        continue;
      case OpCode::kAbs:
        a = std::abs(a);
        continue;
      case OpCode::kFloor:
        a = std::floor(a);
        continue;
      case OpCode::kCeil:
        a = std::ceil(a);
        continue;
      default:
        break;
    }
    const double b = stack[--top];
    double& l = stack[top - 1];
    switch (op.code) {
      case OpCode::kAdd:
        l += b;
        break;
      case OpCode::kSub:
        l -= b;
        break;
      case OpCode::kMul:
        l *= b;
        break;
      case OpCode::kDiv:
        l /= b;
        break;
      case OpCode::kPow:
        l = std::pow(l, b);
        break;
      case OpCode::kMin:
        l = std::min(l, b);
        break;
      case OpCode::kMax:
        l = std::max(l, b);
        break;
      case OpCode::kAtan2:
        l = std::atan2(l, b);
        break;
      default:
        break;
    }
  }
  return top > 0 ? stack[top - 1] : 0.0;
}

}  // namespace hof::haptics
