// State files (app/src/state_file.cpp): what is written is read back bit for bit, and a damaged, foreign
// or mismatched file is refused with one line that names the path and the reason. Whether a restored
// run continues as the saved one would have: tests/sim/restore_test.cpp (the solver) and the headless
// end-to-end test ARunContinuedFromItsStateFileEndsWhereTheWholeRunEnds.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "refusal.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/state_file.h"
#include "sphxr/interaction/paddle.h"
#include "sim_worker.h"  // app/src: DefaultStatePath
#include "support.h"

namespace sphxr::app {
namespace {

using test::ExpectBriefRefusal;
using test::ExpectCleanRefusal;

std::unique_ptr<sim::Solver> SteppedSolver(int steps) {
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f));
  for (int k = 0; solver && k < steps; ++k) EXPECT_TRUE(solver->Step().ok());
  return solver;
}

std::string Bytes(const std::string& path) { return test::ReadFile(path); }

void Put(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void ExpectRefused(const std::string& path, const std::string& needle) {
  StateFile state;
  const Status s = ReadStateFile(path, &state);
  ASSERT_FALSE(s.ok()) << "accepted: " << path;
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line: " << s.message();
}

TEST(StateFile, WhatIsWrittenIsReadBackBitForBit) {
  test::TempDir dir("state_roundtrip");
  auto solver = SteppedSolver(25);
  ASSERT_TRUE(solver);
  const std::string path = dir.File("a.state");
  // As a run continued from a file saved at step 1000 saves it: its own 25 steps counted on from there.
  ASSERT_TRUE(WriteStateFile(path, *solver, "small dam break", nullptr, 0.0, 1000).ok());
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp")) << "the temporary file is renamed into place";

  StateFile state;
  const Status s = ReadStateFile(path, &state);
  ASSERT_TRUE(s.ok()) << s.message();
  sim::HostFluid fluid;
  solver->Download(&fluid);
  EXPECT_EQ(state.scene, "small dam break");
  EXPECT_EQ(state.fluidCount, solver->FluidCount());
  EXPECT_EQ(state.boundaryCount, solver->BoundaryCount());
  EXPECT_EQ(state.spacing, 0.01f);
  EXPECT_EQ(state.clock.time, solver->Time());
  EXPECT_EQ(state.step, 1025);
  EXPECT_EQ(state.clock.lastMaxSpeed, solver->Clock().lastMaxSpeed);
  EXPECT_EQ(state.clock.lastMaxAccel, solver->Clock().lastMaxAccel);
  EXPECT_GT(state.clock.lastMaxSpeed, 0.0f);
  ASSERT_EQ(state.fluid.size(), fluid.size());
#define SPHXR_COMPARE_FIELD(type, name)                                                                 \
  EXPECT_EQ(std::memcmp(state.fluid.name.data(), fluid.name.data(), fluid.name.size() * sizeof(type)), 0) \
      << "field " #name " differs";
  SPHXR_FLUID_FIELDS(SPHXR_COMPARE_FIELD)
#undef SPHXR_COMPARE_FIELD

  // It restores into a fresh solver of the same scene, and the clock comes with it.
  auto fresh = test::CreateOrFail(test::SmallDamBreak(0.01f));
  ASSERT_TRUE(RestoreState(state, fresh.get()).ok());
  EXPECT_EQ(fresh->Time(), solver->Time());
}

TEST(StateFile, DamagedAndForeignFilesAreRefusedByName) {
  test::TempDir dir("state_damaged");
  auto solver = SteppedSolver(3);
  ASSERT_TRUE(solver);
  const std::string good = dir.File("good.state");
  ASSERT_TRUE(WriteStateFile(good, *solver, "s").ok());
  const std::string bytes = Bytes(good);
  ASSERT_GT(bytes.size(), 100u);
  const std::string bad = dir.File("bad.state");

  ExpectRefused(dir.File("missing.state"), "cannot open");
  Put(bad, "{ \"tank\": {} }\n");
  ExpectRefused(bad, "not an sphxr state file");
  Put(bad, bytes.substr(0, bytes.size() / 2));
  ExpectRefused(bad, "truncated");
  Put(bad, bytes.substr(0, 20));
  ExpectRefused(bad, "truncated");
  Put(bad, bytes + "x");
  ExpectRefused(bad, "after the last field");

  // Offsets: magic 8, byte order 4, version 4, time 8, max speed and |a| 4 + 4, step 8, spacing 4.
  constexpr size_t kStepAt = 8 + 4 + 4 + 8 + 2 * 4, kFluidAt = kStepAt + 8 + 4;
  std::string other = bytes;  // a fluid count of 2^31 - 1
  const int32_t huge = 0x7fffffff;
  std::memcpy(&other[kFluidAt], &huge, 4);
  Put(bad, other);
  ExpectRefused(bad, "truncated");  // refused from the file's size, before allocating for it

  other = bytes;  // the version (after 8 bytes of magic and 4 of byte order)
  other[12] = 7;
  Put(bad, other);
  ExpectRefused(bad, "version 7");
  other = bytes;
  const int64_t negative = -5;
  std::memcpy(&other[kStepAt], &negative, 8);
  Put(bad, other);
  ExpectRefused(bad, "step count -5");
  other = bytes;
  const int64_t huge_step = int64_t{1} << 62;  // a flipped high bit
  std::memcpy(&other[kStepAt], &huge_step, 8);
  Put(bad, other);
  ExpectRefused(bad, "step count 4611686018427387904");
  other = bytes;
  std::reverse(&other[8], &other[12]);  // the byte-order mark as the other byte order writes it
  Put(bad, other);
  ExpectRefused(bad, "byte order");
  other = bytes;
  const size_t at = other.find("velocity");
  ASSERT_NE(at, std::string::npos);
  other.replace(at, 8, "velocitx");
  Put(bad, other);
  ExpectRefused(bad, "'velocitx' is not one this build knows");
  other = bytes;  // "density" and "pressure" are both 4-byte fields of the same length: "pressure" twice
  const size_t density = other.find("density");
  ASSERT_NE(density, std::string::npos);
  other.replace(density - 4, 4 + 7, std::string("\x08\0\0\0pressure", 12));
  Put(bad, other.substr(0, other.size()));
  ExpectRefused(bad, "appears twice");
  ExpectRefused(dir.path().string(), "is a directory");
}

// A paddle's saved state is used as it is read (its commanded pose becomes the paddle's target, its
// load the controller's buzz), so a damaged value is refused by the reader, naming the paddle.
TEST(StateFile, APaddleWithANonFiniteStateIsRefused) {
  test::TempDir dir("state_paddle");
  sim::SceneSetup scene = test::SmallDamBreak(0.01f);
  interaction::PaddleDesc desc;
  desc.holder = interaction::Holder::kRightHand;
  desc.shapes = interaction::BladeOnHandle(0.05f, 0.008f, 0.04f, 0.04f, 0.012f);
  std::unique_ptr<interaction::PaddleSystem> paddles;
  const Status c = interaction::PaddleSystem::Create({desc}, scene, &paddles);
  ASSERT_TRUE(c.ok()) << c.message();
  paddles->AddBodies(&scene);
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_TRUE(paddles->Attach(solver.get()).ok());
  ASSERT_TRUE(paddles->BeginFrame(1.0 / 90.0).ok());  // one frame (no hand: the paddle stays withdrawn)
  while (solver->Time() < 0.005 - 1e-9) {
    ASSERT_TRUE(solver->Step().ok());
    paddles->AfterStep();
  }
  const std::string good = dir.File("good.state"), bad = dir.File("bad.state");
  ASSERT_TRUE(WriteStateFile(good, *solver, "s", paddles.get(), 0.005).ok());
  StateFile state;
  ASSERT_TRUE(ReadStateFile(good, &state).ok());
  ASSERT_EQ(state.paddles.size(), 1u);
  EXPECT_EQ(state.paddleClock, 0.005);

  // The paddle's record follows the bodies' motions; its commanded pose is the first after its mode.
  const std::string bytes = Bytes(good);
  const sim::Vec3 commanded = state.paddles[0].state.commanded.position;
  const size_t fields = bytes.find("position");  // the first field's name: the records end before it
  ASSERT_NE(fields, std::string::npos);
  const size_t at = std::string_view(bytes.data(), fields).rfind(std::string_view(reinterpret_cast<const char*>(&commanded), 12));
  ASSERT_NE(at, std::string_view::npos);
  const int32_t mode = static_cast<int32_t>(state.paddles[0].state.mode);  // (withdrawing: no hand holds it)
  ASSERT_EQ(std::memcmp(&bytes[at - 4], &mode, 4), 0) << "the paddle's mode precedes its pose";
  const float nan = std::nanf("");
  std::string other = bytes;
  std::memcpy(&other[at + 4], &nan, 4);  // commanded y
  Put(bad, other);
  ExpectRefused(bad, "paddle 0 has a non-finite pose");
  other = bytes;  // the buzz amplitude: after the pose (12 + 16) and force, torque, raw force (3 x 12)
  const float loud = 3.0f;
  std::memcpy(&other[at + 28 + 36], &loud, 4);
  Put(bad, other);
  ExpectRefused(bad, "buzz outside 0..1");
  other = bytes;  // the paddle clock: the last 8 bytes before the field count and the first field's name
  const double inf = INFINITY;
  std::memcpy(&other[fields - 4 - 4 - 8], &inf, 8);
  Put(bad, other);
  ExpectRefused(bad, "non-finite paddle clock");
}

TEST(StateFile, RecordsTheSolverMethod) {
  test::TempDir dir("state_method");
  sim::SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.method = sim::SolverMethod::kDfsph;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver && test::StepN(*solver, 3));
  const std::string path = dir.File("dfsph.state");
  ASSERT_TRUE(WriteStateFile(path, *solver, "s").ok());
  StateFile read;
  ASSERT_TRUE(ReadStateFile(path, &read).ok());
  EXPECT_EQ(read.method, sim::SolverMethod::kDfsph);
  // Continued under the other method (the scene or --set says so): allowed, and said.
  test::LogCapture log;
  sim::SceneSetup wcsph = test::SmallDamBreak(0.01f);
  std::shared_ptr<const StateFile> start;
  ASSERT_TRUE(ReadStartState(path, 0.0f, "s", &wcsph, &start).ok());
  EXPECT_EQ(log.Count("saved under solver.method dfsph", LogLevel::kWarn), 1) << log.All();
}

// Version 1 files have no step count: it is still read, with the step unknown
// (-1: a continued run numbers from 0), and the fluid as saved.
TEST(StateFile, AVersionOneFileIsReadWithoutItsStepCount) {
  test::TempDir dir("state_v1");
  auto solver = SteppedSolver(4);
  ASSERT_TRUE(solver);
  const std::string v2 = dir.File("v2.state"), v1 = dir.File("v1.state");
  ASSERT_TRUE(WriteStateFile(v2, *solver, "s").ok());
  std::string bytes = Bytes(v2);
  bytes[12] = 1;                            // the version
  bytes.erase(8 + 4 + 4 + 8 + 2 * 4, 8);    // and no step count after the clock
  // nor the solver method (version 3) after the scene's name "s": spacing, two counts, the name
  bytes.erase(8 + 4 + 4 + 8 + 2 * 4 + 4 + 2 * 4 + 4 + 1, 4 + 5);
  bytes.resize(bytes.size() - 4);  // nor the diffuse particles (version 4): their count, 0, at the end
  Put(v1, bytes);
  StateFile a, b;
  ASSERT_TRUE(ReadStateFile(v2, &a).ok());
  const Status s = ReadStateFile(v1, &b);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(a.step, 4);
  EXPECT_EQ(b.step, -1);
  EXPECT_EQ(b.method, sim::SolverMethod::kWcsph) << "files before version 3 ran the only method there was";
  EXPECT_EQ(b.clock.time, a.clock.time);
  EXPECT_EQ(b.spacing, a.spacing);
  ASSERT_EQ(b.fluid.size(), a.fluid.size());
  EXPECT_EQ(std::memcmp(b.fluid.position.data(), a.fluid.position.data(), a.fluid.position.size() * sizeof(a.fluid.position[0])), 0);
  // A run continued from it saves the count as unknown again, not its own steps as the whole run's.
  const std::string again = dir.File("again.state");
  ASSERT_TRUE(WriteStateFile(again, *solver, "s", nullptr, 0.0, b.step).ok());
  StateFile c;
  ASSERT_TRUE(ReadStateFile(again, &c).ok());
  EXPECT_EQ(c.step, -1);
}

/// The small dam break with diffuse particles on (stir.json's ranges: its falling column spawns).
sim::SceneSetup DiffuseDamBreak() {
  sim::SceneSetup scene = test::SmallDamBreak(0.01f);
  SceneFile stir;
  EXPECT_TRUE(LoadScene(SPHXR_SCENES_DIR "/stir.json", &stir).ok());
  for (const sim::ParamInfo& p : sim::SolverParamInfos()) {
    if (std::string(p.key).rfind("diffuse", 0) == 0) scene.params.*p.member = stir.setup.params.*p.member;
  }
  return scene;
}

TEST(StateFile, ADiffuseRunContinuesBitForBit) {
  // The truth is the run that was never stopped: saved once it has spawned, 40 more steps from the file must
  // give the same water and the same spray, foam and bubbles, to the bit.
  test::TempDir dir("state_diffuse");
  auto through = test::CreateOrFail(DiffuseDamBreak());
  ASSERT_TRUE(through);
  for (int k = 0; k < 400 && through->DiffuseCount() < 20; ++k) ASSERT_TRUE(through->Step().ok());
  ASSERT_GE(through->DiffuseCount(), 20) << "the collapsing column should have spawned by 0.4 s";
  const std::string path = dir.File("d.state");
  ASSERT_TRUE(WriteStateFile(path, *through, "d").ok());
  StateFile state;
  ASSERT_TRUE(ReadStateFile(path, &state).ok());
  EXPECT_EQ(state.diffuse.count, through->DiffuseCount());
  auto restored = test::CreateOrFail(DiffuseDamBreak());
  ASSERT_TRUE(restored);
  ASSERT_TRUE(RestoreState(state, restored.get()).ok());
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(through->Step().ok());
    ASSERT_TRUE(restored->Step().ok());
  }
  sim::HostDiffuse a, b;
  through->DownloadDiffuse(&a);
  restored->DownloadDiffuse(&b);
  ASSERT_EQ(a.count, b.count);
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), a.position.size() * sizeof(sim::Vec4)), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), a.velocity.size() * sizeof(sim::Vec4)), 0);
  sim::HostFluid fa, fb;
  through->Download(&fa);
  restored->Download(&fb);
  EXPECT_EQ(std::memcmp(fa.position.data(), fb.position.data(), fa.position.size() * sizeof(sim::Vec4)), 0);
}

TEST(StateFile, AVersionThreeFileLoadsWithoutDiffuseParticles) {
  test::TempDir dir("state_v3");
  auto solver = test::CreateOrFail(DiffuseDamBreak());
  ASSERT_TRUE(solver);
  for (int k = 0; k < 400 && solver->DiffuseCount() == 0; ++k) ASSERT_TRUE(solver->Step().ok());
  const int count = solver->DiffuseCount();
  ASSERT_GT(count, 0);
  const std::string v4 = dir.File("v4.state"), v3 = dir.File("v3.state");
  ASSERT_TRUE(WriteStateFile(v4, *solver, "s").ok());
  std::string bytes = Bytes(v4);
  bytes[12] = 3;                                               // the version
  bytes.resize(bytes.size() - 4 - 2 * sizeof(sim::Vec4) * count);  // the diffuse section at the end
  Put(v3, bytes);
  StateFile state;
  const Status s = ReadStateFile(v3, &state);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(state.diffuse.count, 0);
  auto fresh = test::CreateOrFail(DiffuseDamBreak());
  ASSERT_TRUE(fresh);
  ASSERT_TRUE(RestoreState(state, fresh.get()).ok());
  EXPECT_EQ(fresh->DiffuseCount(), 0);
  ASSERT_TRUE(fresh->Step().ok());
  // A version-4 file with a diffuse count beyond its bytes is truncated, not read past its end.
  bytes = Bytes(v4);
  bytes.resize(bytes.size() - sizeof(sim::Vec4));
  Put(v3, bytes);
  EXPECT_FALSE(ReadStateFile(v3, &state).ok());
}

TEST(StateFile, AnotherSceneOrSpacingIsRefused) {
  test::TempDir dir("state_mismatch");
  auto solver = SteppedSolver(2);
  ASSERT_TRUE(solver);
  const std::string path = dir.File("a.state");
  ASSERT_TRUE(WriteStateFile(path, *solver, "small").ok());
  StateFile state;
  ASSERT_TRUE(ReadStateFile(path, &state).ok());
  auto coarser = test::CreateOrFail(test::SmallDamBreak(0.02f));
  ASSERT_TRUE(coarser);
  const Status s = RestoreState(state, coarser.get());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("saved from 'small'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("another scene"), std::string::npos) << s.message();
  EXPECT_EQ(coarser->Time(), 0.0) << "a refused state changes nothing";
}

// The file is renamed into place, which would replace whatever is there: a pipe or device is refused
// and left alone (--save-state /dev/null, as root, must not replace the system's /dev/null), and a
// symbolic link is followed: the link stays, its target gets the state.
TEST(StateFile, APipeIsRefusedAndALinkIsFollowed) {
  test::TempDir dir("state_nodes");
  auto solver = SteppedSolver(2);
  ASSERT_TRUE(solver);
  const std::string fifo = dir.File("pipe");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const Status s = WriteStateFile(fifo, *solver, "s");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("not a regular file"), std::string::npos) << s.message();
  EXPECT_TRUE(std::filesystem::is_fifo(fifo)) << "the pipe is still a pipe";

  const std::string target = dir.File("target.state"), link = dir.File("link.state");
  Put(target, "old");
  std::filesystem::create_symlink(target, link);
  ASSERT_TRUE(WriteStateFile(link, *solver, "s").ok());
  EXPECT_TRUE(std::filesystem::is_symlink(link)) << "the link is kept";
  StateFile state;
  ASSERT_TRUE(ReadStateFile(target, &state).ok()) << "its target holds the state";
  EXPECT_EQ(state.step, 2);
}

// Without --save-state the window and the headset save to "<scene name>.state": a scene's name from a
// shared file must not name a path ("../escape_dir/evil" would save outside the folder).
TEST(StateFile, TheDefaultSaveNameStaysInTheWorkingDirectory) {
  EXPECT_EQ(DefaultStatePath("dam_break"), "dam_break.state");
  EXPECT_EQ(DefaultStatePath("deep tank v1.2"), "deep_tank_v1.2.state");
  EXPECT_EQ(DefaultStatePath("../escape_dir/evil"), "___escape_dir_evil.state");
  EXPECT_EQ(DefaultStatePath("/abs/x"), "_abs_x.state");
  EXPECT_EQ(DefaultStatePath(""), "sphxr.state");
  EXPECT_EQ(DefaultStatePath("/"), "sphxr.state");
  EXPECT_EQ(DefaultStatePath(".."), "sphxr.state");
}

TEST(StateFile, AFailedWriteLeavesTheEarlierFile) {
  test::TempDir dir("state_failed_write");
  auto solver = SteppedSolver(2);
  ASSERT_TRUE(solver);
  const std::string path = dir.File("a.state");
  ASSERT_TRUE(WriteStateFile(path, *solver, "first").ok());
  const std::string before = Bytes(path);
  // The temporary file cannot be created where a directory of its name stands.
  std::filesystem::create_directory(path + ".tmp");
  ASSERT_TRUE(solver->Step().ok());
  const Status s = WriteStateFile(path, *solver, "second");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_EQ(Bytes(path), before) << "the earlier state file is unchanged";
}

// State files are checked as scenes are: finite but absurd values (every particle outside the tank, a
// body at y = 1e9 m, a particle at 1e9 m/s, two particles with one id) are refused, not restored.
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
  test::TempDir m_dir{"state_checks"};
  sim::SceneSetup m_scene;
  StateFile m_state;
};

TEST_F(StateChecks, TheSavedStateRestores) { EXPECT_TRUE(Restore(m_state).ok()); }

// A damaged field name is refused in one line, not quoted raw with its newlines (a fuzz target's input).
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

// The saved clock is checked as the scene is.
class ClockChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    m_scene = test::SmallDamBreak(0.02f);
    auto solver = test::CreateOrFail(m_scene);
    ASSERT_TRUE(solver);
    ASSERT_TRUE(solver->Step().ok());
    m_path = m_dir.File("clock.state");
    ASSERT_TRUE(WriteStateFile(m_path, *solver, "small").ok());
    ASSERT_TRUE(ReadStateFile(m_path, &m_state).ok());
  }
  Status Restore(const StateFile& state) {
    auto fresh = test::CreateOrFail(m_scene);
    return fresh ? RestoreState(state, fresh.get()) : Status::Error("no solver");
  }
  test::TempDir m_dir{"state_clock"};
  sim::SceneSetup m_scene;
  std::string m_path;
  StateFile m_state;
};

TEST_F(ClockChecks, ASavedMaximumSpeedBeyondTheScenesLimitIsRefusedNamingTheFile) {
  EXPECT_TRUE(Restore(m_state).ok());
  StateFile bad = m_state;
  bad.clock.lastMaxSpeed = 1e30f;
  ExpectCleanRefusal(Restore(bad), m_path);
  ExpectCleanRefusal(Restore(bad), "last maximum speed");
}

TEST_F(ClockChecks, ASavedMaximumAccelerationTheStepCannotResolveIsRefused) {
  StateFile bad = m_state;
  bad.clock.lastMaxAccel = 3.4e38f;
  ExpectCleanRefusal(Restore(bad), m_path);
  ExpectCleanRefusal(Restore(bad), "last maximum acceleration");
}

}  // namespace
}  // namespace sphxr::app
