// Text from users' files made valid UTF-8.

#include "hof/core/text.h"

#include <gtest/gtest.h>

namespace hof {
namespace {

TEST(ValidUtf8, KeepsValidTextAndReplacesEachBadByte) {
  EXPECT_EQ(valid_utf8("Liver"), "Liver");
  EXPECT_EQ(valid_utf8("Gr\xC3\xB6\xC3\x9F" "e"), "Gr\xC3\xB6\xC3\x9F" "e");  // "Größe" in UTF-8
  EXPECT_EQ(valid_utf8("Gr\xF6\xDF" "e"), "Gr\xEF\xBF\xBD\xEF\xBF\xBD" "e");    // the same in Latin-1
  EXPECT_EQ(valid_utf8("end\xE2\x82"), "end\xEF\xBF\xBD\xEF\xBF\xBD");          // cut short
  EXPECT_EQ(valid_utf8("\xF0\x9F\x98\x80"), "\xF0\x9F\x98\x80");                 // four bytes
  EXPECT_EQ(valid_utf8(""), "");
}

}  // namespace
}  // namespace hof
