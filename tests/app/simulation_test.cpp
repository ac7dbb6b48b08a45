// app::Simulation: the run every mode builds. Its sinks see every step once, in order, numbered as the
// whole run; a sink's error stops the run; the frame clock keeps frames on the 1/frame_rate grid;
// AdvanceFrame is one frame of steps, the same bits as the same steps taken one by one; a run rebuilt
// from its own state file steps on bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
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

TEST(SimulationTest, TheFrameClockKeepsFramesOnItsGrid) {
  SimScene scene = Scene(0.01f);
  scene.paddles.push_back(DefaultHandPaddle(scene.setup, 1));
  scene.paddleFrameRate = 50.0;
  std::unique_ptr<Simulation> run;
  const Status c = Simulation::Create(scene, Config(), &run);
  ASSERT_TRUE(c.ok()) << c.message();
  ASSERT_NE(run->Paddles(), nullptr);
  EXPECT_EQ(run->NextFrame(), 0.0) << "from the solver's time";
  double frames = 0.0;  // the clock advances by 1/50 s, from the first step at or past each frame
  while (run->Solver().Time() < 0.05) {
    const double before = run->Solver().Time();
    const double clock = run->NextFrame();
    ASSERT_TRUE(run->Step().ok());
    if (before >= clock - 1e-9) frames += 1.0;
    EXPECT_NEAR(run->NextFrame(), frames / 50.0, 1e-15) << "t = " << before;  // (a sum of 1/50s: rounding)
    EXPECT_GT(run->NextFrame(), before) << "a frame is always ahead of the step that began it";
  }
  EXPECT_EQ(frames, 3.0) << "frames at 0, 0.02 and 0.04 s";
}

/// A scene with the right hand's default paddle, its frames at `frameRate`.
SimScene HandScene(double frameRate = 90.0, sim::SolverMethod method = sim::SolverMethod::kWcsph) {
  SimScene scene = Scene(0.01f);
  scene.setup.method = method;
  scene.paddles.push_back(DefaultHandPaddle(scene.setup, 1));
  scene.paddleFrameRate = frameRate;
  return scene;
}

/// The right hand, tracked at `position`.
std::vector<interaction::HandInput> RightHandAt(sim::Vec3 position) {
  interaction::HandInput hand;
  hand.tracked = true;
  hand.pose.position = position;
  return {interaction::HandInput{}, hand};
}

TEST(SimulationTest, AdvanceFrameIsOneFrameOfStepsWithOnePaddleFrame) {
  std::unique_ptr<Simulation> run;
  const Status c = Simulation::Create(HandScene(50.0), Config(), &run);
  ASSERT_TRUE(c.ok()) << c.message();
  EXPECT_EQ(run->FramePeriod(), 1.0 / 50.0);
  Recorder sink;
  run->AddSink(&sink);
  const interaction::PaddleSystem& paddles = *run->Paddles();
  ASSERT_EQ(paddles.State(0).mode, interaction::PaddleMode::kWithdrawing) << "a hand not seen yet";
  for (int frame = 1; frame <= 3; ++frame) {
    const double end = frame / 50.0;
    const size_t before = sink.times.size();
    const int64_t stepsBefore = run->Solver().GetTotals().steps;
    ASSERT_TRUE(run->AdvanceFrame(RightHandAt({0.15f, 0.12f, 0.03f})).ok());
    EXPECT_NEAR(run->NextFrame(), end, 1e-15) << "one frame begun, one period on";
    // The sinks saw each of the frame's steps once; the frame ends at the first step at or past its end.
    const int64_t steps = run->Solver().GetTotals().steps - stepsBefore;
    ASSERT_GT(steps, 1);
    ASSERT_EQ(sink.times.size() - before, static_cast<size_t>(steps));
    for (size_t k = before; k + 1 < sink.times.size(); ++k) EXPECT_LT(sink.times[k], end - 1e-9) << "frame " << frame;
    EXPECT_GE(sink.times.back(), end - 1e-9) << "frame " << frame;
    EXPECT_EQ(sink.times.back(), run->Solver().Time());
    // The hands reached the paddles once, at the frame's begin: the first tracked frame is a re-entry.
    EXPECT_EQ(paddles.State(0).teleports, 1) << "frame " << frame;
    EXPECT_NE(paddles.State(0).mode, interaction::PaddleMode::kWithdrawing) << "frame " << frame;
  }
}

TEST(SimulationTest, AFrameCutShortByAfterStepIsFinishedByTheNextCall) {
  std::unique_ptr<Simulation> run;
  ASSERT_TRUE(Simulation::Create(HandScene(), Config(), &run).ok());
  int calls = 0;
  ASSERT_TRUE(run->AdvanceFrame({}, [&] { return ++calls < 2; }).ok());
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(run->Solver().GetTotals().steps, 2) << "stopped after the step that said no";
  EXPECT_EQ(run->NextFrame(), run->FramePeriod());
  EXPECT_LT(run->Solver().Time(), run->NextFrame() - 1e-9);
  calls = 0;
  ASSERT_TRUE(run->AdvanceFrame({}, [&] { return ++calls > 0; }).ok());
  EXPECT_EQ(run->NextFrame(), run->FramePeriod()) << "the same frame, finished: no new one begun";
  EXPECT_GE(run->Solver().Time(), run->NextFrame() - 1e-9);
  EXPECT_EQ(calls, run->Solver().GetTotals().steps - 2) << "called after every step";
}

TEST(SimulationTest, WithoutPaddlesAFrameIsStillOnePeriod) {
  std::unique_ptr<Simulation> run;
  ASSERT_TRUE(Simulation::Create(Scene(), Config(), &run).ok());
  ASSERT_EQ(run->Paddles(), nullptr);
  ASSERT_TRUE(run->AdvanceFrame().ok());
  EXPECT_EQ(run->NextFrame(), 1.0 / 90.0);
  EXPECT_GE(run->Solver().Time(), run->NextFrame() - 1e-9);
  EXPECT_GT(run->Solver().GetTotals().steps, 1);
}

TEST(SimulationTest, ANewFrameRateTakesEffectAtTheNextFrameAndOutOfRangeIsRefused) {
  std::unique_ptr<Simulation> run;
  ASSERT_TRUE(Simulation::Create(Scene(), Config(), &run).ok());
  ASSERT_TRUE(run->AdvanceFrame().ok());
  const double firstEnd = run->NextFrame();
  ASSERT_TRUE(run->SetFrameRate(72.0).ok());  // a headset displaying at 72 Hz
  EXPECT_EQ(run->NextFrame(), firstEnd);       // the frame under way keeps its end
  ASSERT_TRUE(run->AdvanceFrame().ok());
  EXPECT_EQ(run->FramePeriod(), 1.0 / 72.0);
  EXPECT_EQ(run->NextFrame(), firstEnd + 1.0 / 72.0);
  EXPECT_EQ(run->Solver().Scene().params.pbfFrame, 1.0f / 72.0f);  // PBF substeps the new frame
  for (double hz : {0.0, -90.0, 0.5, 5000.0, std::numeric_limits<double>::quiet_NaN(),
                    std::numeric_limits<double>::infinity()}) {
    const Status s = run->SetFrameRate(hz);
    EXPECT_FALSE(s.ok()) << hz;
    EXPECT_NE(s.message().find("out of range"), std::string::npos) << s.message();
  }
  EXPECT_EQ(run->FramePeriod(), 1.0 / 72.0);  // a refused rate changes nothing
}

// The frame call is the single steps grouped: a run by frames and a run by steps, given the same hands
// for each frame, have the same steps, the same frames and the same bits.
class SimulationFrames : public ::testing::TestWithParam<sim::SolverMethod> {};

TEST_P(SimulationFrames, ARunByFramesIsTheRunByStepsBitForBit) {
  std::unique_ptr<Simulation> frames, steps;
  ASSERT_TRUE(Simulation::Create(HandScene(90.0, GetParam()), Config(), &frames).ok());
  ASSERT_TRUE(Simulation::Create(HandScene(90.0, GetParam()), Config(), &steps).ok());
  for (int frame = 0; frame < 6; ++frame) {
    const float x = 0.1f + 0.01f * static_cast<float>(frame);  // a hand stirring along x
    const std::vector<interaction::HandInput> hands = RightHandAt({x, 0.1f, 0.03f});
    ASSERT_TRUE(frames->AdvanceFrame(hands).ok());
    while (steps->Solver().GetTotals().steps < frames->Solver().GetTotals().steps) {
      ASSERT_TRUE(steps->Step(hands).ok());
    }
    ASSERT_EQ(steps->NextFrame(), frames->NextFrame()) << "frame " << frame;
    ASSERT_EQ(steps->Solver().Time(), frames->Solver().Time()) << "frame " << frame;
  }
  const sim::HostFluid a = test::DownloadFluid(frames->Solver()), b = test::DownloadFluid(steps->Solver());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), a.size() * sizeof(a.position[0])), 0);
  EXPECT_EQ(std::memcmp(a.velocity.data(), b.velocity.data(), a.size() * sizeof(a.velocity[0])), 0);
  const auto pa = frames->Solver().BodyPose(frames->Paddles()->BodyIndex(0));
  const auto pb = steps->Solver().BodyPose(steps->Paddles()->BodyIndex(0));
  EXPECT_EQ(std::memcmp(&pa, &pb, sizeof(pa)), 0);
  const sim::Vec3 fa = frames->Paddles()->State(0).force, fb = steps->Paddles()->State(0).force;
  EXPECT_EQ(std::memcmp(&fa, &fb, sizeof(fa)), 0);
}

INSTANTIATE_TEST_SUITE_P(Methods, SimulationFrames,
                         ::testing::Values(sim::SolverMethod::kWcsph, sim::SolverMethod::kDfsph, sim::SolverMethod::kPbf),
                         [](const auto& info) { return std::string(sim::SolverMethodName(info.param)); });

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
  EXPECT_EQ(second->NextFrame(), first->NextFrame());
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
