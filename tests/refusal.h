#pragma once
// What a refusal of hostile or careless input looks like to the user: one line that names the key (or
// the option, the file, the field) and is short enough to read, at once; the clean form also holds that
// nothing in it is a byte or code point a terminal would act on (ESC, C1, bidi, U+2028).
#include <gtest/gtest.h>

#include <string>

#include "sphxr/common/shown_text.h"
#include "sphxr/common/status.h"

namespace sphxr::test {

// A refusal: one line, naming `needle`, short enough to read (a bad value is echoed in at most ~80
// characters).
inline void ExpectBriefRefusal(const Status& s, const std::string& needle) {
  ASSERT_FALSE(s.ok()) << "accepted";
  EXPECT_NE(s.message().find(needle), std::string::npos) << s.message().substr(0, 400);
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line";
  EXPECT_LT(s.message().size(), 300u) << s.message().substr(0, 400);
}

// One line, naming `needle`, short, and nothing a terminal would act on (ESC, C1, bidi, U+2028).
inline void ExpectCleanRefusal(const Status& s, const std::string& needle, size_t longest = 300) {
  ASSERT_FALSE(s.ok()) << "accepted";
  const std::string& m = s.message();
  EXPECT_NE(m.find(needle), std::string::npos) << m.substr(0, 400);
  EXPECT_LT(m.size(), longest) << m.substr(0, 400);
  for (const unsigned char c : m) EXPECT_FALSE(c < 0x20 || c == 0x7f) << "control byte " << int(c) << " in " << m.substr(0, 400);
  for (const char* hidden : {"\xC2\x85", "\xC2\x9B", "\xE2\x80\xAE", "\xE2\x80\xA8"}) {
    EXPECT_EQ(m.find(hidden), std::string::npos) << m.substr(0, 400);
  }
  EXPECT_TRUE(IsPlainText(m)) << "not plain text (invalid UTF-8 or a hidden code point): " << ShowText(m, 400);
}

}  // namespace sphxr::test
