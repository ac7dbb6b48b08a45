// Text shown to a user (common/src/shown_text.cpp): every class of hidden character escaped, long values
// cut with their length, never half an escape or half a character at the cut; lists cut with a count.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sphxr/common/shown_text.h"

namespace sphxr {
namespace {

TEST(ShownText, EscapesEveryHiddenClassAndCutsLongValues) {
  EXPECT_EQ(ShowText("a\x1b[2Jb\n"), "a\\x1B[2Jb\\x0A");
  EXPECT_EQ(ShowText("\xC2\x85\xC2\x9B\xE2\x80\xAE\xE2\x80\xA8\xE2\x80\xA9\xEF\xBB\xBF"), "\\u0085\\u009B\\u202E\\u2028\\u2029\\uFEFF");
  EXPECT_EQ(ShowText("\xF3\xA0\x80\x81"), "\\U000E0001") << "a tag character (Cf) beyond the BMP";
  EXPECT_EQ(ShowText("\xFF\xC0\xAF"), "\\xFF\\xC0\\xAF") << "bytes that are not UTF-8 (an overlong '/')";
  EXPECT_EQ(ShowText("\xC3\xBC \xE6\xB0\xB4 \xE2\x80\x93"), "\xC3\xBC \xE6\xB0\xB4 \xE2\x80\x93") << "plain UTF-8 stays";
  const std::string cut = ShowText(std::string(5000, 'x'));
  EXPECT_EQ(cut, std::string(kShownLength, 'x') + "... (5000 bytes)");
  // Never half an escape or half a character at the cut.
  const std::string escapes = ShowText(std::string(100, '\x07'), 10);
  EXPECT_EQ(escapes, "\\x07\\x07... (100 bytes)");
  EXPECT_EQ(ShowText(ShowText("a\xE2\x80\xAE" "b", 1000), 1000), ShowText("a\xE2\x80\xAE" "b", 1000)) << "idempotent";
  EXPECT_TRUE(IsPlainText("Becken \xC3\xBC"));
  EXPECT_FALSE(IsPlainText("a\xE2\x80\xAE"));
  EXPECT_FALSE(IsPlainText("a\xC2\x85"));
  EXPECT_FALSE(IsPlainText("a\xFF"));
  std::vector<std::string> names;
  for (int k = 0; k < 1025; ++k) names.push_back("p" + std::to_string(k));
  const std::string list = ShowList(names);
  EXPECT_EQ(list, "p0, p1, p2, p3, p4, p5, p6, p7 and 1017 more");
}

}  // namespace
}  // namespace sphxr
