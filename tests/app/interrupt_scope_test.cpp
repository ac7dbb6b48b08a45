// The interrupts of a run (app/src/interrupt_scope.h): a second SIGINT 5 ms after the first still lets the
// headless run end as one interrupted run, with its summary, whole CSV rows and no temporary state file.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "sphxr/app/state_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

const char* kSmallScene = R"({
  "name": "interrupt",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } ]
})";

TEST(InterruptProcess, TwoInterruptsFiveMillisecondsApartLeaveTheSummaryAndNoTemporaryFile) {
  test::TempDir dir("interrupt");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string csv = dir.File("stats.csv"), state = dir.File("s.state");
  const std::string outPath = dir.File("out.txt"), errPath = dir.File("err.txt");
  const pid_t pid = test::SpawnSphxr({"--headless", "--scene", scene, "--steps", "100000000", "--stats", csv,
                                      "--threads", "1", "--no-progress", "--save-state", state,
                                      "--checkpoint-every", "0.001"},
                                     outPath, errPath);
  ASSERT_GE(pid, 0);
  test::WaitForFileSize(csv, 4096, std::chrono::milliseconds(20));
  ASSERT_EQ(kill(pid, SIGINT), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string out = test::ReadFile(outPath), err = test::ReadFile(errPath);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the second SIGINT:\n" << err;
  EXPECT_EQ(WEXITSTATUS(status), 130) << err;
  EXPECT_NE(out.find("interrupted     by SIGINT"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(state + ".tmp"));
  const std::vector<std::string> rows = test::Lines(test::ReadFile(csv));
  ASSERT_GT(rows.size(), 2u);
  const size_t commas = std::count(rows[0].begin(), rows[0].end(), ',');
  for (size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(static_cast<size_t>(std::count(rows[i].begin(), rows[i].end(), ',')), commas) << "row " << i;
  }
  StateFile saved;
  EXPECT_TRUE(ReadStateFile(state, &saved).ok());
}

}  // namespace
}  // namespace sphxr::app
