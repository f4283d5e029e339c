// Functions given as text (src/hof/haptics/function_expression.cpp), as H3D's GeneralFunction
// takes them: precedence and associativity as in mathematics, every function against the C++
// library, variables bound in the order given, and each kind of bad text a parse error that
// quotes it.

#include "hof/haptics/function_expression.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

namespace hof::haptics {
namespace {

// Copied into the haptic loop by value, so it must copy without allocating.
static_assert(std::is_trivially_copyable_v<FunctionExpression>);

const std::vector<std::string> kXyz{"x", "y", "z"};

double value(const std::string& text, std::vector<double> values = {}) {
  const auto f = FunctionExpression::make(text, kXyz);
  EXPECT_TRUE(f.has_value()) << text << ": " << (f ? "" : f.error().to_string());
  return f ? f->evaluate(values) : std::numeric_limits<double>::quiet_NaN();
}

std::string error_of(const std::string& text, const std::vector<std::string>& variables = kXyz) {
  const auto f = FunctionExpression::make(text, variables);
  EXPECT_FALSE(f.has_value()) << "'" << text << "' compiled";
  if (f) return "";
  EXPECT_EQ(f.error().code, ErrorCode::kParse);
  return f.error().to_string();
}

TEST(FunctionExpression, PrecedenceAndAssociativityAreMathematics) {
  EXPECT_EQ(value("1 + 2 * 3"), 7.0);
  EXPECT_EQ(value("(1 + 2) * 3"), 9.0);
  EXPECT_EQ(value("10 - 4 - 3"), 3.0);   // left to right
  EXPECT_EQ(value("8 / 4 / 2"), 1.0);    // left to right
  EXPECT_EQ(value("2 ^ 3 ^ 2"), 512.0);  // right to left: 2^9
  EXPECT_EQ(value("-2 ^ 2"), -4.0);      // the power binds tighter than the sign
  EXPECT_EQ(value("2 ^ -1"), 0.5);
  EXPECT_EQ(value("--3"), 3.0);
  EXPECT_EQ(value("+3"), 3.0);
  EXPECT_EQ(value("2 * -3"), -6.0);
  EXPECT_EQ(value("1e3 + .5"), 1000.5);
  EXPECT_EQ(value("  ( ( 4 ) )  "), 4.0);
}

TEST(FunctionExpression, FunctionsAreTheLibrarysAndPiIsPi) {
  // Within 4 ulps: the compiler may fold the expected values with another library.
  const double a = 0.3, b = -1.7;
  EXPECT_DOUBLE_EQ(value("sin(0.3)"), std::sin(a));
  EXPECT_DOUBLE_EQ(value("cos(0.3)"), std::cos(a));
  EXPECT_DOUBLE_EQ(value("tan(0.3)"), std::tan(a));
  EXPECT_DOUBLE_EQ(value("asin(0.3)"), std::asin(a));
  EXPECT_DOUBLE_EQ(value("acos(0.3)"), std::acos(a));
  EXPECT_DOUBLE_EQ(value("atan(0.3)"), std::atan(a));
  EXPECT_DOUBLE_EQ(value("exp(0.3)"), std::exp(a));
  EXPECT_DOUBLE_EQ(value("log(0.3)"), std::log(a));
  EXPECT_DOUBLE_EQ(value("sqrt(0.3)"), std::sqrt(a));
  EXPECT_EQ(value("abs(-1.7)"), std::abs(b));
  EXPECT_EQ(value("floor(-1.7)"), -2.0);
  EXPECT_EQ(value("ceil(-1.7)"), -1.0);
  EXPECT_EQ(value("min(0.3, -1.7)"), b);
  EXPECT_EQ(value("max(0.3, -1.7)"), a);
  EXPECT_DOUBLE_EQ(value("atan2(0.3, -1.7)"), std::atan2(a, b));
  EXPECT_DOUBLE_EQ(value("pow(0.3, -1.7)"), std::pow(a, b));
  EXPECT_EQ(value("pi"), std::numbers::pi);
  EXPECT_DOUBLE_EQ(value("sin(pi / 6) * 2 + max(1, min(2, 3))"), std::sin(std::numbers::pi / 6) * 2 + 2);
}

TEST(FunctionExpression, VariablesAreBoundInTheOrderGiven) {
  EXPECT_EQ(value("x - 2*y + 3*z", {1, 2, 3}), 6.0);
  const std::vector<std::string> reversed{"z", "y", "x"};
  const auto f = FunctionExpression::make("x - 2*y + 3*z", reversed);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->evaluate(std::vector<double>{1, 2, 3}), 3.0 - 4.0 + 3.0);
  const std::vector<std::string> named{"t_1", "speed2"};
  const auto g = FunctionExpression::make("t_1 * speed2", named);
  ASSERT_TRUE(g);
  EXPECT_EQ(g->evaluate(std::vector<double>{1.5, 4}), 6.0);
  // A value not given reads as 0.
  EXPECT_EQ(value("x + y + z + 1", {5}), 6.0);
  // A variable may shadow a function's or the constant's name.
  const std::vector<std::string> pi{"pi"};
  const auto h = FunctionExpression::make("2 * pi", pi);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->evaluate(std::vector<double>{3}), 6.0);
}

TEST(FunctionExpression, OutOfDomainGivesNaNOrInfinityNotACrash) {
  EXPECT_TRUE(std::isnan(value("sqrt(-1)")));
  EXPECT_TRUE(std::isnan(value("log(-1)")));
  EXPECT_EQ(value("1 / 0"), std::numeric_limits<double>::infinity());
  EXPECT_EQ(value("-1 / 0"), -std::numeric_limits<double>::infinity());
}

TEST(FunctionExpression, BadTextIsAParseErrorQuotingItAndSayingWhere) {
  EXPECT_NE(error_of("").find("unexpected end"), std::string::npos);
  EXPECT_NE(error_of("1 +").find("'1 +': unexpected end"), std::string::npos);
  EXPECT_NE(error_of("(1 + 2").find("expected ')' at character 7"), std::string::npos);
  EXPECT_NE(error_of("2x").find("unexpected 'x' at character 2"), std::string::npos);  // no implicit product
  EXPECT_NE(error_of("1.2.3").find("unexpected '.' at character 4"), std::string::npos);
  EXPECT_NE(error_of("3 # 4").find("unexpected '#' at character 3"), std::string::npos);
  EXPECT_NE(error_of("sin 1").find("expected '('"), std::string::npos);
  EXPECT_NE(error_of("min(1)").find("expected ','"), std::string::npos);
  EXPECT_NE(error_of("sinh(x)").find("unknown name 'sinh' (the variables are: x, y, z)"), std::string::npos);
  EXPECT_NE(error_of("t", {}).find("unknown name 't' (the variables are: none)"), std::string::npos);
  const std::vector<std::string> four{"a", "b", "c", "d"};
  EXPECT_NE(error_of("a", four).find("at most 3 variables, got 4"), std::string::npos);
}

TEST(FunctionExpression, ProgramsLongerThanTheBudgetOrNestedTooDeeplyAreRefused) {
  // "1+1+...+1" with n ones is 2n − 1 operations: 48 fit in 96, 49 do not.
  const auto ones = [](int n) {
    std::string text = "1";
    for (int i = 1; i < n; ++i) text += "+1";
    return text;
  };
  EXPECT_EQ(value(ones(48)), 48.0);
  EXPECT_NE(error_of(ones(49)).find("longer than 96 operations"), std::string::npos);
  // Right-nested sums keep every operand on the stack: 32 fit, 33 do not.
  const auto nested = [](int n) {
    std::string text;
    for (int i = 1; i < n; ++i) text += "1+(";
    text += "1";
    text += std::string(static_cast<std::size_t>(n - 1), ')');
    return text;
  };
  EXPECT_EQ(value(nested(32)), 32.0);
  EXPECT_NE(error_of(nested(33)).find("nested too deeply"), std::string::npos);
}

}  // namespace
}  // namespace hof::haptics
