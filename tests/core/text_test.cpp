// Text from users' files made valid UTF-8; how far a mistyped name is from a known one.

#include "hof/core/text.h"

#include <gtest/gtest.h>

namespace hof {
namespace {

TEST(ValidUtf8, KeepsValidTextAndReplacesEachBadByte) {
  EXPECT_EQ(valid_utf8("Liver"), "Liver");
  EXPECT_EQ(valid_utf8("Gr\xC3\xB6\xC3\x9F"
                       "e"),
            "Gr\xC3\xB6\xC3\x9F"
            "e");  // "Größe" in UTF-8
  EXPECT_EQ(valid_utf8("Gr\xF6\xDF"
                       "e"),
            "Gr\xEF\xBF\xBD\xEF\xBF\xBD"
            "e");                                                       // the same in Latin-1
  EXPECT_EQ(valid_utf8("end\xE2\x82"), "end\xEF\xBF\xBD\xEF\xBF\xBD");  // cut short
  EXPECT_EQ(valid_utf8("\xF0\x9F\x98\x80"), "\xF0\x9F\x98\x80");        // four bytes
  EXPECT_EQ(valid_utf8(""), "");
}

TEST(EditDistance, CountsInsertionsDeletionsAndSubstitutionsIgnoringCase) {
  EXPECT_EQ(edit_distance("", ""), 0U);
  EXPECT_EQ(edit_distance("dt", ""), 2U);
  EXPECT_EQ(edit_distance("", "dt"), 2U);
  EXPECT_EQ(edit_distance("youngModulus", "youngModulus"), 0U);
  EXPECT_EQ(edit_distance("youngmodulus", "YoungModulus"), 0U) << "case is ignored";
  EXPECT_EQ(edit_distance("youngModulu", "youngModulus"), 1U);  // a letter left out
  EXPECT_EQ(edit_distance("stiffnes", "stiffness"), 1U);
  EXPECT_EQ(edit_distance("damping", "dampign"), 2U);  // two letters swapped: two substitutions
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3U);
  EXPECT_EQ(edit_distance("MeshSpringForceField", "MeshSpringForceFeild"),
            edit_distance("MeshSpringForceFeild", "MeshSpringForceField"));
}

TEST(BlankSeparatedWords, SplitsOnSpacesTabsAndCarriageReturnsOnly) {
  using V = std::vector<std::string_view>;
  EXPECT_EQ(blank_separated_words("  sphe 0.5\t-1e-3  2 \r"), (V{"sphe", "0.5", "-1e-3", "2"}));
  EXPECT_EQ(blank_separated_words("a,b;c"), (V{"a,b;c"}));  // only blanks separate
  EXPECT_TRUE(blank_separated_words(" \t\r ").empty());
  EXPECT_TRUE(blank_separated_words("").empty());
}

}  // namespace
}  // namespace hof
