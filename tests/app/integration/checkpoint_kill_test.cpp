// Nothing lost to a kill: a headless run with --stats and --checkpoint-every killed with
// SIGKILL 10 s in leaves a CSV of whole rows and a state file from which the run continues, its rows
// appended after the checkpoint's step as the whole run numbers them.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sphxr/app/state_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

using test::Lines;
using test::SpawnSphxr;

size_t Commas(const std::string& s) { return static_cast<size_t>(std::count(s.begin(), s.end(), ',')); }

// Every row whole (as many columns as the header, ended by a newline) and the steps 1, 2, 3, ...
void ExpectWholeRowsInOrder(const std::string& csv, int64_t* lastStep) {
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv.back(), '\n') << "a torn last row";
  const std::vector<std::string> lines = Lines(csv);
  ASSERT_GE(lines.size(), 2u) << "no rows";
  for (size_t i = 1; i < lines.size(); ++i) {
    ASSERT_EQ(Commas(lines[i]), Commas(lines[0])) << "row " << i << ": " << lines[i];
    ASSERT_EQ(std::stoll(lines[i]), static_cast<long long>(i)) << "row " << i << ": " << lines[i];
  }
  *lastStep = static_cast<int64_t>(lines.size()) - 1;
}

TEST(CheckpointKill, ASigkillLeavesWholeRowsAndACheckpointThatContinues) {
  test::TempDir dir("checkpoint_kill");
  // The stirring scene (a paddle, so that the paddle state is checkpointed too) with its trajectory, at
  // 2 cm (1,700 particles: many checkpoints in 10 s on a busy machine).
  std::filesystem::copy_file(SPHXR_SCENES_DIR "/stir.json", dir.File("stir.json"));
  std::filesystem::copy_file(SPHXR_SCENES_DIR "/stir_paddle.csv", dir.File("stir_paddle.csv"));
  const std::string scene = dir.File("stir.json"), csv = dir.File("stats.csv"), state = dir.File("run.state");
  const pid_t pid = SpawnSphxr({"--headless", "--scene", scene, "--spacing", "0.02", "--time", "1000", "--threads", "1", "--no-progress",
                           "--stats", csv, "--save-state", state, "--checkpoint-every", "0.1"},
                          dir.File("out.txt"), dir.File("err.txt"));
  ASSERT_GT(pid, 0);
  std::this_thread::sleep_for(std::chrono::seconds(10));
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before the kill:\n" << test::ReadFile(dir.File("err.txt"));

  int64_t killedAt = 0;
  ExpectWholeRowsInOrder(test::ReadFile(csv), &killedAt);
  StateFile saved;
  const Status read = ReadStateFile(state, &saved);
  ASSERT_TRUE(read.ok()) << read.message();
  EXPECT_GT(saved.clock.time, 0.05) << "no checkpoint in 10 s";
  EXPECT_GE(killedAt, saved.step) << "the CSV is flushed before each checkpoint";
  EXPECT_FALSE(std::filesystem::exists(state + ".tmp")) << "a checkpoint is renamed into place";

  // The run continues from the checkpoint: its rows replace those after the checkpoint's step.
  const double end = saved.clock.time + 0.02;
  const pid_t again = SpawnSphxr({"--headless", "--scene", scene, "--load-state", state, "--time", std::to_string(end),
                             "--threads", "1", "--no-progress", "--stats", csv},
                            dir.File("out2.txt"), dir.File("err2.txt"));
  ASSERT_GT(again, 0);
  ASSERT_EQ(waitpid(again, &status, 0), again);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::ReadFile(dir.File("err2.txt"));
  int64_t lastStep = 0;
  ExpectWholeRowsInOrder(test::ReadFile(csv), &lastStep);
  EXPECT_GT(lastStep, saved.step);
}

}  // namespace
}  // namespace sphxr::app
