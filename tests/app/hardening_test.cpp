// Inputs a user (or an attacker) can give that used to crash, hang, eat gigabytes or win silently
// (issue 39): each must now be refused in one short line, at once, before anything large is allocated.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "sphxr/app/cli.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/headless.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/state_file.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/interaction/trajectory.h"
#include "sphxr/common/log.h"
#include "support.h"

namespace sphxr::app {
namespace {

// A refusal: one line, naming `needle`, short enough to read (a bad value is echoed in at most ~80
// characters).
void ExpectBriefRefusal(const Status& s, const std::string& needle) {
  ASSERT_FALSE(s.ok()) << "accepted";
  EXPECT_NE(s.message().find(needle), std::string::npos) << s.message().substr(0, 400);
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line";
  EXPECT_LT(s.message().size(), 300u) << s.message().substr(0, 400);
}

Status Parse(const std::string& text, SceneFile* scene) { return ParseScene(text, "test.json", scene); }

double SecondsOf(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(Hardening, DeepNestingIsRefusedNotACrash) {
  // 100,000 levels: the message printed the value with a recursive dump and overflowed the stack.
  const std::string deep = R"({"tank": {"min": )" + std::string(100000, '[') + std::string(100000, ']') +
                           R"(, "max": [1,1,1]}})";
  SceneFile scene;
  ExpectBriefRefusal(Parse(deep, &scene), "nested more than 64 levels");
  // 40 levels is legal JSON nesting, and the message about the wrong type stays short.
  const std::string forty = R"({"tank": {"min": )" + std::string(40, '[') + std::string(40, ']') + R"(, "max": [1,1,1]}})";
  ExpectBriefRefusal(Parse(forty, &scene), "tank.min");
}

TEST(Hardening, AHugeValueIsEchoedInAtMost80Characters) {
  SceneFile scene;
  const std::string text = R"({"tank": {"min": [0, 0, ")" + std::string(5000000, 'a') + R"("], "max": [1,1,1]}})";
  ExpectBriefRefusal(Parse(text, &scene), "tank.min[2]: must be a number");
  std::string many;
  for (int k = 0; k < 100000; ++k) many += "1,";
  const std::string array = R"({"tank": {"min": [)" + many + R"(2], "max": [1,1,1]}})";
  ExpectBriefRefusal(Parse(array, &scene), "tank.min");
  // An unterminated 5 MB string: the parser's own message quotes what it read last.
  ExpectBriefRefusal(Parse(R"({"name": ")" + std::string(5000000, 'b'), &scene), "not valid JSON");
}

TEST(Hardening, DuplicateKeysAreRefusedNamingTheKeyAndBothLines) {
  SceneFile scene;
  const std::string twoSolvers = "{\n  \"solver\": {\"stiffness\": 2e5},\n  \"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]},\n"
                                 "  \"solver\": {\"spacing\": 0.05}\n}";
  ExpectBriefRefusal(Parse(twoSolvers, &scene), "key \"solver\" appears twice at the top level (lines 2 and 4)");
  const std::string twoFluids = "{\"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]},\n\"fluid\": [{\"min\": [0,0,0], "
                                "\"max\": [0.5,0.5,0.5]}],\n\"fluid\": []}";
  ExpectBriefRefusal(Parse(twoFluids, &scene), "key \"fluid\" appears twice");
  // Inside a section, and spelt with an escape: the parser reads "sp\u0061cing" as "spacing".
  const std::string nested = "{\"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]},\n\"solver\": {\"spacing\": 0.1,\n"
                             "  \"sp\\u0061cing\": 0.05}}";
  ExpectBriefRefusal(Parse(nested, &scene), "appears twice in solver (lines 2 and 3)");
  // The same key in two objects is fine.
  const std::string fine = R"({"tank": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [{"min": [0,0,0], "max": [1,0.5,1]}]})";
  EXPECT_TRUE(Parse(fine, &scene).ok());
}

TEST(Hardening, AHundredThousandKeysParseAtOnceWithFewWarnings) {
  std::string text = R"({"tank": {"min": [0,0,0], "max": [1,1,1]})";
  for (int k = 0; k < 100000; ++k) text += ",\"k" + std::to_string(k) + "\": 1";
  text += "}";
  SceneFile scene;
  const LogLevel level = GetLogLevel();
  SetLogLevel(LogLevel::kError);
  Status s;
  const double seconds = SecondsOf([&] { s = Parse(text, &scene); });
  SetLogLevel(level);
  EXPECT_TRUE(s.ok()) << s.message();
  // (0.3 s in a release build, 3 s under the sanitizers; a quadratic check takes minutes.)
  EXPECT_LT(seconds, 20.0) << "the duplicate check is not quadratic";
  ASSERT_EQ(scene.warnings.size(), 21u) << "20 by name, then one line counting the rest";
  EXPECT_EQ(scene.warnings.back(), "99980 more unknown keys ignored");
}

TEST(Hardening, NamesWithTerminalEscapesAreRefused) {
  SceneFile scene;
  ExpectBriefRefusal(Parse("{\"name\": \"\\u001b[31mred\", \"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]}}", &scene),
                     "name: \\x1B[31mred: has control, format or line-separator characters");
}

TEST(Hardening, TrajectoryValuesBeyondAFloatNameTheFileAndLine) {
  for (const char* value : {"1e300", "3e38", "-3e38"}) {
    interaction::Trajectory t;
    const std::string text = std::string("time,px,py,pz\n0,0.1,0.1,0.1\n1,") + value + ",0.1,0.1\n";
    ExpectBriefRefusal(interaction::Trajectory::Parse(text, "hand.csv", &t), "hand.csv:3: column 2");
  }
  interaction::Trajectory t;
  ExpectBriefRefusal(interaction::Trajectory::Parse("0,0,0,0\n1e12,0,0,0\n", "hand.csv", &t), "hand.csv:2: column 1");
  ExpectBriefRefusal(interaction::Trajectory::Parse("0,0,0,0\n1,0,0," + std::string(10000, '9') + "x\n", "hand.csv", &t),
                     "is not a finite number");
}

// A paddle far larger than the tank was sampled (8.9 GB for a capsule of radius 100 m) before its
// size was checked.
TEST(Hardening, AHugePaddleIsRefusedBeforeItIsSampled) {
  const sim::SceneSetup scene = test::SmallDamBreak(0.01f);
  for (const sim::ShapePrimitive& shape :
       {sim::ShapePrimitive{sim::ShapePrimitive::Kind::kCapsule, {0, 0, 0}, {0, 0, 0}, 100.0f},
        sim::ShapePrimitive{sim::ShapePrimitive::Kind::kBox, {0, 0, 0}, {6e9f, 0.01f, 0.01f}, 0.0f}}) {
    interaction::PaddleDesc d;
    d.name = "big";
    d.holder = interaction::Holder::kLeftHand;
    d.shapes = {shape};
    std::unique_ptr<interaction::PaddleSystem> system;
    Status s;
    const double seconds = SecondsOf([&] { s = interaction::PaddleSystem::Create({d}, scene, &system); });
    ExpectBriefRefusal(s, "more than the tank's");
    EXPECT_LT(seconds, 1.0);
  }
}

// With an obstacle the particle count walked a lattice of 1.7e9 sites (20 s) before refusing it.
TEST(Hardening, ATinySpacingWithObstaclesIsRefusedAtOnce) {
  sim::SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.25f, 0.3f}, 0.0002f);
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.15f, 0.3f}));
  scene.obstacles.push_back(test::Box({0.1f, 0, 0.1f}, {0.2f, 0.05f, 0.2f}));
  std::unique_ptr<sim::Solver> solver;
  Status s;
  const double seconds = SecondsOf([&] { s = sim::Solver::Create(scene, test::TestConfig(), &solver); });
  ExpectBriefRefusal(s, "up to");
  EXPECT_LT(seconds, 1.0);
}

TEST(Hardening, ACommandLineGivesEachOptionOnceAndOneMode) {
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

TEST(Hardening, AFifoIsRefusedAsAnInputInsteadOfBlocking) {
  test::TempDir dir("hardening_fifo");
  const std::string fifo = dir.File("scene.fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  SceneFile scene;
  ExpectBriefRefusal(LoadScene(fifo, &scene), "not a regular file");
  interaction::Trajectory t;
  ExpectBriefRefusal(interaction::Trajectory::Load(fifo, &t), "not a regular file");
}

// `--save-state link.csv --stats z.csv` with link.csv -> z.csv, z.csv not there yet: the state
// overwrote the statistics.
TEST(Hardening, ADanglingSymlinkDoesNotDefeatTheOutputClashCheck) {
  test::TempDir dir("hardening_link");
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

TEST(Hardening, OutputDirectoriesAreMadeOnlyInADirectoryThatExists) {
  test::TempDir dir("hardening_outdir");
  const std::string scene = dir.Write("scene.json", test::kSmallTankScene);
  Options options;
  options.scenePath = scene;
  options.steps = 1;
  options.threads = 1;
  options.progress = 0;
  options.exportEvery = 1;
  options.outDir = dir.File("missing/out");
  RunSummary summary;
  ExpectBriefRefusal(RunHeadless(options, &summary), "does not exist; make it first");
  EXPECT_FALSE(std::filesystem::exists(dir.File("missing")));
  options.outDir = dir.File("out/");  // one level is made
  EXPECT_TRUE(RunHeadless(options, &summary).ok());
  EXPECT_TRUE(std::filesystem::is_directory(dir.File("out")));
  options.exportEvery = 0;
  options.outDir = "out";
  options.statsPath = dir.File("missing/stats.csv");
  ExpectBriefRefusal(RunHeadless(options, &summary), "does not exist; make it first");
}

// A --save-state that fails after the run (a full disk; here its temporary file's place is taken by
// a directory) is one error line after the summary, not instead of it.
TEST(Hardening, AFailedSaveStillPrintsTheSummary) {
  test::TempDir dir("hardening_save");
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

// State files are checked as scenes are: finite but absurd values were restored (every particle
// outside the tank, a body at y = 1e9 m, a particle at 1e9 m/s, two particles with one id).
class StateChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    m_scene = test::SmallDamBreak(0.01f);
    auto solver = test::CreateOrFail(m_scene);
    ASSERT_TRUE(solver);
    ASSERT_TRUE(solver->Step().ok());
    ASSERT_TRUE(WriteStateFile(m_dir.File("a.state"), *solver, "small").ok());
    ASSERT_TRUE(ReadStateFile(m_dir.File("a.state"), &m_state).ok());
  }
  Status Restore(const StateFile& state) {
    auto fresh = test::CreateOrFail(m_scene);
    return fresh ? RestoreState(state, fresh.get()) : Status::Error("no solver");
  }
  test::TempDir m_dir{"hardening_state"};
  sim::SceneSetup m_scene;
  StateFile m_state;
};

TEST_F(StateChecks, TheSavedStateRestores) { EXPECT_TRUE(Restore(m_state).ok()); }

// Found by the fuzz target: a damaged field name was quoted raw, newlines and all.
TEST_F(StateChecks, ADamagedFieldNameIsRefusedInOneLine) {
  std::string bytes = test::ReadFile(m_dir.File("a.state"));
  const size_t at = bytes.find("velocity");
  ASSERT_NE(at, std::string::npos);
  bytes[at + 3] = '\n';
  StateFile state;
  ExpectBriefRefusal(ParseStateFile(std::vector<char>(bytes.begin(), bytes.end()), "a.state", &state), "has no name");
}

TEST_F(StateChecks, ParticlesOutsideTheTankAreRefused) {
  StateFile s = m_state;
  for (sim::Vec4& p : s.fluid.position) p.x += 10.0f;
  ExpectBriefRefusal(Restore(s), "outside the tank");
}

TEST_F(StateChecks, ASpeedBeyondTheScenesLimitIsRefused) {
  StateFile s = m_state;
  s.fluid.velocity[5].y = 1e9f;
  ExpectBriefRefusal(Restore(s), "moves at 1e+09 m/s");
}

TEST_F(StateChecks, DuplicateIdsAreRefused) {
  StateFile s = m_state;
  s.fluid.id[3] = s.fluid.id[4];
  ExpectBriefRefusal(Restore(s), "appears twice");
}

TEST_F(StateChecks, ABodyFarFromTheTankIsRefused) {
  // The scene with one paddle, saved, then its pose moved to y = 1e9 m.
  sim::SceneSetup scene = m_scene;
  interaction::PaddleDesc d;
  d.name = "p";
  d.holder = interaction::Holder::kLeftHand;
  d.shapes = {sim::ShapePrimitive{sim::ShapePrimitive::Kind::kBox, {0, 0, 0}, {0.01f, 0.03f, 0.01f}, 0.0f}};
  std::unique_ptr<interaction::PaddleSystem> paddles;
  ASSERT_TRUE(interaction::PaddleSystem::Create({d}, scene, &paddles).ok());
  paddles->AddBodies(&scene);
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_TRUE(WriteStateFile(m_dir.File("b.state"), *solver, "small").ok());
  StateFile state;
  ASSERT_TRUE(ReadStateFile(m_dir.File("b.state"), &state).ok());
  ASSERT_EQ(state.bodies.size(), 1u);
  auto fresh = test::CreateOrFail(scene);
  EXPECT_TRUE(RestoreState(state, fresh.get()).ok());
  state.bodies[0].pose.position.y = 1e9f;
  auto again = test::CreateOrFail(scene);
  ExpectBriefRefusal(RestoreState(state, again.get()), "body 0's pose");
}

}  // namespace
}  // namespace sphxr::app
