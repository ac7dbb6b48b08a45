// The arguments of a run (app/run_arguments.h), one table for the command line, the Python module and
// the sweeps: the same bounds and messages, thread counts bounded by the machine and by what the
// process may start, range messages with the digits that put a value out, a scene name echoed once.
// (The module's side: tests/python/test_run_arguments.py.)
#include "sphxr/app/run_arguments.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "sphxr/app/cli.h"
#include "sphxr/app/param_registry.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/openmp_wait.h"
#include "support.h"

namespace sphxr::app {
namespace {

// One line, naming every needle, short, nothing a terminal would act on.
void ExpectOneLine(const Status& s, const std::vector<std::string>& needles, size_t longest = 400) {
  ASSERT_FALSE(s.ok()) << "accepted";
  const std::string& m = s.message();
  for (const std::string& n : needles)
    EXPECT_NE(m.find(n), std::string::npos) << "no '" << n << "' in " << m.substr(0, 400);
  EXPECT_LT(m.size(), longest) << m.substr(0, 400);
  EXPECT_TRUE(IsPlainText(m)) << ShowText(m, 400);
}

Status ParseArgs(std::vector<std::string> args) {
  args.insert(args.begin(), "sphxr");
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  Options o;
  return ParseCommandLine(static_cast<int>(argv.size()), argv.data(), &o);
}

TEST(RunArguments, TheCommandLineAndTheModuleShareTheBoundsAndTheMessages) {
  // The command line reads the text, the module checks the number: one rule, one message.
  const struct {
    const char* flag;
    const char* text;
    double value;
    const char* message;
  } cases[] = {
      {"--settle", "4000", 4000.0, "settle 4000: must be from 0 to 3600 s"},
      {"--settle", "-1", -1.0, "settle -1: must be from 0 to 3600 s"},
      {"--time", "1e300", 1e300, "time 1e300: must be from 1e-09 to 1e+06 s"},
  };
  for (const auto& c : cases) {
    const Status cli = ParseArgs({c.flag, c.text});
    ExpectOneLine(cli, {std::string("--") + c.message});
    const Status module = CheckRunArgument(c.flag + 2, c.value);
    if (std::string(c.flag) == "--settle") EXPECT_EQ("--" + module.message(), cli.message());
  }
  ExpectOneLine(ParseArgs({"--time", "nan"}), {"--time nan: not a finite number"});
  ExpectOneLine(ParseArgs({"--steps", "-5"}), {"--steps -5: must be from 1 to 1099511627776"});
  ExpectOneLine(CheckRunArgument("run_to", std::numeric_limits<double>::infinity()),
                {"run_to inf: not a finite number"});
  ExpectOneLine(CheckRunArgument("advance", -0.5), {"advance -0.5: must be from 0 to 1e+06 s"});
  ExpectOneLine(CheckRunArgument("step", 2.5), {"step 2.5: not a whole number"});
  double v = 0.0;
  ExpectOneLine(ParseRunArgument("--workers", "0", &v), {"--workers 0: must be from 1 to"});
  ExpectOneLine(ParseRunArgument("--time", "0x10", &v), {"--time 0x10: not a decimal number"});
  ExpectOneLine(ParseRunArgument("--time",
                                 std::string("1\0"
                                             "2",
                                             3),
                                 &v),
                {"--time 1\\x002: not a number"});
  ASSERT_TRUE(ParseRunArgument("--time", "0.25", &v).ok());
  EXPECT_EQ(v, 0.25);
}

TEST(RunArguments, ThreadCountsAreBoundedByTheMachine) {
  const int most = sim::MaxSolverThreads();
  EXPECT_GE(most, 64);
  ASSERT_TRUE(ParseArgs({"--threads", std::to_string(most)}).ok());
  ExpectOneLine(ParseArgs({"--threads", std::to_string(most + 1)}),
                {"--threads " + std::to_string(most + 1) + ": must be from 0 to " + std::to_string(most)});
  ExpectOneLine(ParseArgs({"--threads", "1000000000"}), {"--threads 1000000000: must be from 0 to"});
  ExpectOneLine(CheckRunArgument("threads", 1e9), {"threads 1000000000: must be from 0 to"});
  // The solver's own check, for a caller that bypasses both (a library user).
  sim::SolverConfig config = test::TestConfig();
  config.threads = most + 1;
  std::unique_ptr<sim::Solver> solver;
  ExpectOneLine(sim::Solver::Create(test::SmallDamBreak(0.02f), config, &solver), {"threads", "must be from 0"});
  EXPECT_TRUE(sim::CheckThreadsCanStart(4, "threads 4").ok());
}

TEST(RunArguments, AFileNameWithANulByteIsRefused) {
  ExpectOneLine(CheckPathArgument("save_state", std::string("a\0b.state", 9)), {"save_state a\\x00b.state", "NUL"});
  ExpectOneLine(CheckPathArgument("save_state", ""), {"save_state: give a file name"});
  EXPECT_TRUE(CheckPathArgument("load_state", "", false).ok());
}

TEST(RunArguments, ARangeMessageShowsTheDigitsThatPutTheValueOut) {
  // pbf_relaxation is from 1e-06 to 10: 10.0000001 printed as "10" read "10 is out of range".
  SceneFile scene;
  ExpectOneLine(
      ParseScene(R"({"tank": {"min": [0, 0, 0], "max": [1, 1, 1]}, "solver": {"pbf_relaxation": 10.0000001}})",
                 "x.json", &scene),
      {"10.0000001 is out of range: must be from 1e-06 to 10"});
  // The registry's check (--set reuse.*, the panel): a value a ten-millionth past the top.
  const ParamDesc* threshold = FindParam("reuse.threshold");
  ASSERT_NE(threshold, nullptr);
  sim::SceneSetup setup;
  const double past = threshold->max * (1.0 + 1e-7);
  ExpectOneLine(SetParam(*threshold, past, "reuse.threshold", &setup),
                {"reuse.threshold: " + ShowNumber(past) + " is out of range: must be from " +
                 ShowNumber(threshold->min) + " to " + ShowNumber(threshold->max)});
  EXPECT_NE(ShowNumber(past), ShowNumber(threshold->max));
  EXPECT_EQ(ShowNumber(10.0000001), "10.0000001");
  EXPECT_EQ(ShowNumber(1e-6), "1e-06");
  EXPECT_EQ(ShowNumber(3600.0), "3600");
}

TEST(RunArguments, AMissingScenesNameIsShownOnceEscapedAndCut) {
  std::string path;
  const std::string name = "x\x1b]0;t\x07" + std::string(100000, 'a');
  const Status s = FindScene(name, &path);
  ExpectOneLine(s, {"--scene x\\x1B]0;t\\x07aaa", "... (100007 bytes): no scene of that name"});
  EXPECT_EQ(s.message().find("aaaa", s.message().find("bytes)")), std::string::npos)
      << "the name twice: " << s.message();
  // A path that cannot be read: the reason survives the name's length.
  SceneFile scene;
  const std::string far = "/no_such_folder/" + std::string(100000, 'b') + "\x1b";
  ExpectOneLine(LoadScene(far, &scene), {"/no_such_folder/bbb", "... (100017 bytes): cannot open the scene file"});
}

#ifdef SPHXR_BINARY
// Threads the process may not start (a limit on processes, ulimit -u) are our one line, not libgomp's
// "Thread creation failed" and its exit. RLIMIT_NPROC does not bind root: the child runs as nobody.
TEST(RunArgumentsProcess, ThreadsTheProcessMayNotStartAreOneLine) {
  test::TempDir dir("run_arguments_threads");
  const std::string outPath = dir.File("out.txt"), errPath = dir.File("err.txt");
  const pid_t pid = test::SpawnSphxr({"--headless", "--scene", SPHXR_SCENES_DIR "/dam_break.json", "--steps", "1",
                                      "--threads", "60", "--no-progress"},
                                     outPath, errPath, [] {
                                       if (getuid() == 0 && (setgid(65534) != 0 || setuid(65534) != 0)) _exit(126);
                                       const rlimit limit{8, 8};
                                       if (setrlimit(RLIMIT_NPROC, &limit) != 0 || chdir("/") != 0) _exit(126);
                                     });
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string err = test::ReadFile(errPath);
  ASSERT_TRUE(WIFEXITED(status)) << err;
  ASSERT_NE(WEXITSTATUS(status), 126) << "could not become nobody or set the limit";
  EXPECT_EQ(WEXITSTATUS(status), 1) << err;
  std::vector<std::string> errors;
  for (const std::string& line : test::Lines(err)) {
    if (line.find("error") != std::string::npos || line.find("libgomp") != std::string::npos) errors.push_back(line);
  }
  ASSERT_EQ(errors.size(), 1u) << err;
  EXPECT_EQ(errors[0].rfind("sphxr: error: ", 0), 0u) << err;
  EXPECT_NE(errors[0].find("threads 60: this process cannot start 60 threads"), std::string::npos) << err;
  EXPECT_NE(errors[0].find("give fewer threads"), std::string::npos) << err;
}
#endif

}  // namespace
}  // namespace sphxr::app
