#include "hof/core/error.h"

#include <gtest/gtest.h>

namespace hof {
namespace {

TEST(Error, NamesFileAndLine) {
  const Error e{ErrorCode::kParse, "expected a number", "liver.msh", 12, -1};
  EXPECT_EQ(e.to_string(), "liver.msh:12: expected a number");
}

TEST(Error, NamesByteOffsetForBinaryFiles) {
  const Error e{ErrorCode::kParse, "truncated", "a.stl", 0, 84};
  EXPECT_EQ(e.to_string(), "a.stl: byte 84: truncated");
}

TEST(Error, MessageAloneWhenNoFile) {
  auto r = make_error(ErrorCode::kInvalidArgument, "bad value");
  EXPECT_EQ(r.error().to_string(), "bad value");
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace hof
