// The command line (app/src/cli.cpp): each option once and one mode, values echoed escaped and cut,
// options that would do nothing refused in one line, and an output that is another's file under a
// dangling link. (Parsing the options' values: headless_test.cpp, CommandLineTest.)
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "refusal.h"
#include "sphxr/app/cli.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/scene_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

using test::ExpectBriefRefusal;
using test::ExpectCleanRefusal;

TEST(Cli, ACommandLineGivesEachOptionOnceAndOneMode) {
  auto parse = [](std::vector<const char*> args) {
    args.insert(args.begin(), "sphxr");
    Options o;
    return ParseCommandLine(static_cast<int>(args.size()), args.data(), &o);
  };
  ExpectBriefRefusal(parse({"--scene", ""}), "--scene: give a file name");
  ExpectBriefRefusal(parse({"--xr", "--desktop"}), "--xr and --desktop: give one");
  ExpectBriefRefusal(parse({"--headless", "--desktop"}), "--headless and --desktop: give one");
  ExpectBriefRefusal(parse({"--steps", "3", "--steps", "4"}), "--steps is given twice");
  ExpectBriefRefusal(parse({"--progress", "--no-progress"}), "give one");
  ExpectBriefRefusal(parse({"--spacing", "0.02", "--set", "spacing=0.01"}), "--spacing and --set spacing=0.01");
  EXPECT_TRUE(parse({"--set", "cfl=0.3", "--set", "stiffness=1e5", "--headless"}).ok()) << "--set repeats";
}

// `--save-state link.csv --stats z.csv` with link.csv -> z.csv, z.csv not there yet: the state would
// overwrite the statistics.
TEST(Cli, ADanglingSymlinkDoesNotDefeatTheOutputClashCheck) {
  test::TempDir dir("cli_link");
  const std::string scene = dir.Write("scene.json", test::kSmallTankScene);
  const std::string link = dir.File("link.csv"), target = dir.File("z.csv");
  std::filesystem::create_symlink("z.csv", link);  // relative, dangling
  Options options;
  options.scenePath = scene;
  options.saveState = link;
  options.statsPath = target;
  SceneFile loaded;
  ExpectBriefRefusal(LoadSceneWithOptions(options, &loaded), "is also --stats's file");
  // A chain of links, the last one dangling.
  const std::string chain = dir.File("chain.csv");
  std::filesystem::create_symlink(link, chain);
  options.saveState = chain;
  ExpectBriefRefusal(LoadSceneWithOptions(options, &loaded), "is also --stats's file");
}

TEST(Cli, CommandLineValuesAreEchoedEscapedAndCut) {
  sim::SceneSetup setup;
  ExpectCleanRefusal(SetSolverParam(&setup, "stiffness=" + std::string(5000, '9')), "stiffness");
  ExpectCleanRefusal(SetSolverParam(&setup, "foo=1"), "unknown parameter", 400);
  ExpectCleanRefusal(SetSolverParam(&setup, "foo\x1b]0;x\x07=1"), "unknown parameter", 400);
  Options o;
  const std::string longPath = std::string(5000, 'p');
  const std::string escape = "1\x1b[2J\n2";
  const char* threads[] = {"sphxr", "--threads", escape.c_str()};
  ExpectCleanRefusal(ParseCommandLine(3, threads, &o), "--threads");
  const char* unknown[] = {"sphxr", longPath.c_str()};
  ExpectCleanRefusal(ParseCommandLine(2, unknown, &o), "unknown argument");
  const char* device[] = {"sphxr", "--device", longPath.c_str()};
  ExpectCleanRefusal(ParseCommandLine(3, device, &o), "--device");
}

TEST(Cli, OptionsWithoutEffectAreRefusedInOneLine) {
  struct Case {
    std::vector<const char*> args;
    const char* needle;
  } cases[] = {
      {{"--checkpoint-keep", "3", "--save-state", "a.state"}, "--checkpoint-keep"},
      {{"--fps", "60"}, "--fps"},
      {{"--surface-format", "obj"}, "--surface-format"},
      {{"--export-format", "vtk"}, "--export-format"},
      {{"--headless", "--window-size", "800x600"}, "--window-size"},
      {{"--headless", "--frame-limit", "10"}, "--frame-limit"},
      {{"--headless", "--render", "particles"}, "--render"},
      {{"--screenshot", ""}, "--screenshot"},
      {{"--stats", "--validate"}, "--stats"},
      {{"--probes", "--headless"}, "--probes"},
  };
  for (const Case& c : cases) {
    std::vector<const char*> argv{"sphxr"};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    Options o;
    ExpectCleanRefusal(ParseCommandLine(static_cast<int>(argv.size()), argv.data(), &o), c.needle);
  }
  // With what they act on, they are taken.
  const char* fine[] = {"sphxr", "--frames", "dir", "--fps", "60", "--export-surface-every", "5", "--surface-format",
                        "obj", "--out", "o", "--headless", "--render", "particles"};
  Options o;
  EXPECT_TRUE(ParseCommandLine(14, fine, &o).ok());
  // A value that starts with a dash is still a value where the option takes numbers.
  const char* negative[] = {"sphxr", "--set", "gravity_y=-9.81"};
  EXPECT_TRUE(ParseCommandLine(3, negative, &o).ok());
}

}  // namespace
}  // namespace sphxr::app
