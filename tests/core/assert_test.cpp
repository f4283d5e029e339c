#include "hof/core/assert.h"

#include <gtest/gtest.h>

namespace hof {
namespace {

int evaluations = 0;
bool counted_true() {
  ++evaluations;
  return true;
}

TEST(AssertDeathTest, CheckAbortsNamingConditionMessageAndLine) {
  EXPECT_DEATH(HOF_CHECK(1 + 1 == 3, "arithmetic is broken"),
               "assert_test.cpp:[0-9]+: assertion failed: 1 \\+ 1 == 3 \\(arithmetic is broken\\)");
}

TEST(AssertTest, CheckPassesSilentlyAndEvaluatesOnce) {
  evaluations = 0;
  HOF_CHECK(counted_true(), "never fails");
  EXPECT_EQ(evaluations, 1);
}

#ifdef NDEBUG
TEST(AssertTest, DebugAssertionIsNotEvaluatedInReleaseBuilds) {
  evaluations = 0;
  HOF_ASSERT(counted_true());
  HOF_ASSERT(1 + 1 == 3);  // compiled, not checked
  EXPECT_EQ(evaluations, 0);
}
#else
TEST(AssertDeathTest, DebugAssertionAbortsWhereAssertionsAreOn) {
  EXPECT_DEATH(HOF_ASSERT(1 + 1 == 3), "assertion failed: 1 \\+ 1 == 3\n");
}
#endif

}  // namespace
}  // namespace hof
