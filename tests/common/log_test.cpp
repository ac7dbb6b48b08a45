// The logger (common/src/log.cpp) shows what a message quotes escaped: a quoted newline cannot forge a
// second line.
#include <gtest/gtest.h>

#include "sphxr/common/log.h"
#include "support.h"

namespace sphxr {
namespace {

TEST(Log, EscapesWhatAMessageQuotes) {
  test::LogCapture log;
  SPHXR_LOG_WARN("name %s", "x\nsphxr: error: forged\x1b]0;t\x07");
  ASSERT_EQ(log.Messages().size(), 1u);
  EXPECT_EQ(log.Messages()[0].text, "name x\\x0Asphxr: error: forged\\x1B]0;t\\x07");
}

}  // namespace
}  // namespace sphxr
