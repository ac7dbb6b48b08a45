// `--stats FILE.csv` (app/src/stats_sink.cpp) when things go wrong: a full disk leaves
// the file at a whole row and says so in one line; a run continued under another method refuses to
// rewrite the first half's rows.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <string>
#include <vector>

#include "support.h"

namespace sphxr {
namespace {

#ifdef SPHXR_BINARY

const char* kScene = R"({
  "name": "stats_file",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } ]
})";

struct Result {
  int code = -1;
  std::string out, err;
};

// The program with `args`; with `fileLimit` > 0, its files may not grow past that many bytes (a disk
// that fills: RLIMIT_FSIZE, its signal ignored so that the write fails with EFBIG).
Result RunSphxr(const test::TempDir& dir, const std::vector<std::string>& args, rlim_t fileLimit = 0) {
  const std::string outPath = dir.File("out.txt"), errPath = dir.File("err.txt");
  const pid_t pid = test::SpawnSphxr(args, outPath, errPath, [fileLimit] {
    if (fileLimit > 0) {
      ::signal(SIGXFSZ, SIG_IGN);
      const rlimit limit{fileLimit, fileLimit};
      if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(126);
    }
  });
  int status = 0;
  waitpid(pid, &status, 0);
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = test::ReadFile(outPath);
  r.err = test::ReadFile(errPath);
  return r;
}

std::vector<std::string> ErrorLines(const std::string& err) {
  std::vector<std::string> lines;
  for (const std::string& line : test::Lines(err)) {
    if (line.find("error") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

TEST(StatsFileProcess, AFullDiskEndsTheFileAtAWholeRowWithOneLine) {
  test::TempDir dir("stats_full");
  const std::string scene = dir.Write("scene.json", kScene), csv = dir.File("stats.csv");
  const Result r =
      RunSphxr(dir,
               {"--headless", "--scene", scene, "--steps", "3000", "--stats", csv, "--threads", "1", "--no-progress"},
               20000);
  EXPECT_EQ(r.code, 1) << r.err;
  const std::vector<std::string> errors = ErrorLines(r.err);
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_NE(errors[0].find("--stats " + csv + ": write failed (File too large); the file ends at its last whole row"),
            std::string::npos)
      << errors[0];
  const std::string text = test::ReadFile(csv);
  ASSERT_GT(text.size(), 1000u);
  ASSERT_LE(text.size(), 20000u);
  EXPECT_EQ(text.back(), '\n') << "a torn last row: ..." << text.substr(text.size() - 80);
  const std::vector<std::string> rows = test::Lines(text);
  const auto commas = std::count(rows[0].begin(), rows[0].end(), ',');
  for (size_t i = 1; i < rows.size(); ++i)
    ASSERT_EQ(std::count(rows[i].begin(), rows[i].end(), ','), commas) << "row " << i;
}

TEST(StatsFileProcess, ContinuingUnderAnotherMethodKeepsTheEarlierRowsAndRefuses) {
  test::TempDir dir("stats_method");
  const std::string scene = dir.Write("scene.json", kScene), csv = dir.File("stats.csv"), state = dir.File("a.state");
  const std::vector<std::string> common = {"--headless", "--scene",       scene,     "--threads",
                                           "1",          "--no-progress", "--stats", csv};
  std::vector<std::string> first = common;
  first.insert(first.end(), {"--steps", "20", "--save-state", state});
  Result r = RunSphxr(dir, first);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string before = test::ReadFile(csv);
  ASSERT_EQ(test::Lines(before).size(), 21u);
  std::vector<std::string> second = common;
  second.insert(second.end(), {"--steps", "40", "--load-state", state, "--set", "method=dfsph"});
  r = RunSphxr(dir, second);
  EXPECT_EQ(r.code, 1) << r.err;
  const std::vector<std::string> errors = ErrorLines(r.err);
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_NE(errors[0].find("--stats " + csv + ": the earlier run's rows there have other columns"), std::string::npos)
      << errors[0];
  EXPECT_NE(errors[0].find("give another --stats file"), std::string::npos) << errors[0];
  EXPECT_EQ(test::ReadFile(csv), before) << "the first half's rows were rewritten";
  // The same method continues the file, as before.
  second.resize(second.size() - 2);
  r = RunSphxr(dir, second);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string after = test::ReadFile(csv);
  EXPECT_EQ(after.rfind(before, 0), 0u);
  EXPECT_EQ(test::Lines(after).size(), 61u);  // the header, 20 rows and 40
}

#endif

}  // namespace
}  // namespace sphxr
