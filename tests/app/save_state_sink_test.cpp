// The save-state sink (app/src/save_state_sink.cpp): a state that cannot be saved after the run is one error
// line after the summary.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "support.h"

namespace sphxr::app {
namespace {

// A --save-state that fails after the run (a full disk; here its temporary file's place is taken by
// a directory) is one error line after the summary, not instead of it.
TEST(SaveStateSink, AFailedSaveStillPrintsTheSummary) {
  test::TempDir dir("sinks_save");
  const std::string scene = dir.Write("scene.json", test::kSmallTankScene);
  const std::string state = dir.File("end.state");
  std::filesystem::create_directory(state + ".tmp");
  const std::string errPath = dir.File("err.txt");
  const std::string command = std::string(SPHXR_BINARY) + " --headless --scene '" + scene + "' --steps 2 --threads 1 " +
                              "--no-progress --save-state '" + state + "' 2>'" + errPath + "'";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_TRUE(pipe);
  std::string out;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof(buffer), pipe)) out.append(buffer, n);
  const int status = pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << status;
  EXPECT_NE(out.find("sphxr summary"), std::string::npos) << out;
  const std::string err = test::ReadFile(errPath);
  const size_t at = err.find("sphxr: error: --save-state");
  ASSERT_NE(at, std::string::npos) << err;
  EXPECT_EQ(err.find('\n', at), err.size() - 1) << "one line, the last: " << err;
}

}  // namespace
}  // namespace sphxr::app
