// app::Simulation: the run every mode builds. Its sinks see every step once, in order, numbered as the
// whole run; a sink's error stops the run; the paddle clock keeps frames on the 1/frame_rate grid, and
// a run rebuilt from its own state file steps on bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

#include "sphxr/app/simulation.h"
#include "sphxr/app/state_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

struct Recorder : SimulationSink {
  int starts = 0, finishes = 0;
  bool interrupted = false;
  std::vector<int64_t> steps;
  std::vector<double> times;
  Status fail;  // returned from the step numbered failAt
  int64_t failAt = -1;
  Status OnStart(Simulation&) override {
    ++starts;
    return Status::Ok();
  }
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override {
    steps.push_back(simulation.WholeStep());
    times.push_back(info.time);
    return simulation.WholeStep() == failAt ? fail : Status::Ok();
  }
  Status Finish(Simulation&, bool stopped) override {
    ++finishes;
    interrupted = stopped;
    return Status::Ok();
  }
};

SimScene Scene(float spacing = 0.02f) {
  SimScene scene;
  scene.name = "small";
  scene.setup = test::SmallDamBreak(spacing);
  return scene;
}

SimulationConfig Config() {
  SimulationConfig config;
  config.solver = test::TestConfig();
  return config;
}

TEST(SimulationTest, SinksSeeEveryStepOnceInOrder) {
  std::unique_ptr<Simulation> run;
  ASSERT_TRUE(Simulation::Create(Scene(), Config(), &run).ok());
  Recorder a, b;
  run->AddSink(&a);
  run->AddSink(&b);
  ASSERT_TRUE(run->Start().ok());
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(run->Step().ok());
  ASSERT_TRUE(run->Finish(true).ok());
  for (const Recorder* r : {&a, &b}) {
    EXPECT_EQ(r->starts, 1);
    EXPECT_EQ(r->finishes, 1);
    EXPECT_TRUE(r->interrupted);
    EXPECT_EQ(r->steps, (std::vector<int64_t>{1, 2, 3, 4, 5}));
  }
  EXPECT_EQ(a.times.back(), run->Solver().Time()) << "the step's own info";
}

TEST(SimulationTest, ASinksErrorStopsTheRunWithIt) {
  std::unique_ptr<Simulation> run;
  ASSERT_TRUE(Simulation::Create(Scene(), Config(), &run).ok());
  Recorder failing, after;
  failing.failAt = 2;
  failing.fail = Status::Error("disk full");
  run->AddSink(&failing);
  run->AddSink(&after);
  ASSERT_TRUE(run->Step().ok());
  const Status s = run->Step();
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.message(), "disk full");
  EXPECT_EQ(after.steps, (std::vector<int64_t>{1})) << "the sinks after it do not see the failed step";
}

TEST(SimulationTest, ThePaddleClockKeepsFramesOnItsGrid) {
  SimScene scene = Scene(0.01f);
  scene.paddles.push_back(DefaultHandPaddle(scene.setup, 1));
  scene.paddleFrameRate = 50.0;
  std::unique_ptr<Simulation> run;
  const Status c = Simulation::Create(scene, Config(), &run);
  ASSERT_TRUE(c.ok()) << c.message();
  ASSERT_NE(run->Paddles(), nullptr);
  EXPECT_EQ(run->PaddleClock(), 0.0) << "from the solver's time";
  double frames = 0.0;  // the clock advances by 1/50 s, from the first step at or past each frame
  while (run->Solver().Time() < 0.05) {
    const double before = run->Solver().Time();
    const double clock = run->PaddleClock();
    ASSERT_TRUE(run->Step().ok());
    if (before >= clock - 1e-9) frames += 1.0;
    EXPECT_NEAR(run->PaddleClock(), frames / 50.0, 1e-15) << "t = " << before;  // (a sum of 1/50s: rounding)
    EXPECT_GT(run->PaddleClock(), before) << "a frame is always ahead of the step that began it";
  }
  EXPECT_EQ(frames, 3.0) << "frames at 0, 0.02 and 0.04 s";
}

TEST(SimulationTest, ARunRebuiltFromItsStateFileStepsOnBitForBit) {
  test::TempDir dir("simulation_restart");
  SimScene scene = Scene(0.01f);
  scene.paddles.push_back(DefaultHandPaddle(scene.setup, 1));
  std::unique_ptr<Simulation> first;
  ASSERT_TRUE(Simulation::Create(scene, Config(), &first).ok());
  for (int k = 0; k < 7; ++k) ASSERT_TRUE(first->Step().ok());
  const std::string path = dir.File("run.state");
  ASSERT_TRUE(first->WriteState(path, scene.name).ok());
  auto state = std::make_shared<StateFile>();
  ASSERT_TRUE(ReadStateFile(path, state.get()).ok());
  SimScene again = scene;
  again.start = state;
  std::unique_ptr<Simulation> second;
  ASSERT_TRUE(Simulation::Create(again, Config(), &second).ok());
  EXPECT_TRUE(second->Restored());
  EXPECT_EQ(second->StepsBefore(), 7);
  EXPECT_EQ(second->PaddleClock(), first->PaddleClock());
  for (int k = 0; k < 5; ++k) {
    ASSERT_TRUE(first->Step().ok());
    ASSERT_TRUE(second->Step().ok());
  }
  EXPECT_EQ(second->WholeStep(), first->WholeStep());
  const sim::HostFluid a = test::DownloadFluid(first->Solver()), b = test::DownloadFluid(second->Solver());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), a.size() * sizeof(a.position[0])), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), a.size() * sizeof(a.velocity[0])), 0);
}

}  // namespace
}  // namespace sphxr::app
