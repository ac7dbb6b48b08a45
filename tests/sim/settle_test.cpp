// Solver::Settle: FIRE (Bitzek et al. 2006) on the solver's own steps before a run
// (docs/design/settle.md). A minimiser goes downhill: the energy after settling longer is lower, measured by
// sim/measure.h SphEnergy (its own kernel, densities recomputed in double precision), with walls that
// have their own density so that fluid and walls are one Hamiltonian system (energy_test.cpp). Then the
// bookkeeping: the clock and the step count restart at 0 with every particle at rest, progress is
// reported and can stop it, and bad calls are refused. Whether the settled water then stays put is the
// hydrostatic validation test's question (tests/validation/hydrostatic_test.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "sphxr/sim/measure.h"
#include "sphxr/sim/solver.h"
#include "support.h"
#include "test_scenes.h"

namespace sphxr::sim {
namespace {

SceneSetup Tank() { return test::SmallRestTank(SceneSetup::WallPressure::kWallDensity, 0.3f); }

EnergySummary Energy(const Solver& solver) {
  HostFluid fluid;
  HostBoundary walls;
  solver.Download(&fluid);
  solver.DownloadBoundary(&walls);
  return SphEnergy(solver.Scene(), solver.ParticleMass(), fluid, walls);
}

TEST(SettleTest, GoesDownhillInEnergyAndEndsAtRest) {
  const SceneSetup scene = Tank();
  std::unique_ptr<Solver> start;
  ASSERT_TRUE(Solver::Create(scene, ::sphxr::test::AllCoresConfig(), &start).ok());
  double previous = Energy(*start).Total();
  // The CPU backend is deterministic: settling for 2 s passes through the state settled for 1 s.
  for (double time : {0.5, 1.0, 2.0}) {
    std::unique_ptr<Solver> solver;
    ASSERT_TRUE(Solver::Create(scene, ::sphxr::test::AllCoresConfig(), &solver).ok());
    SettleReport report;
    ASSERT_TRUE(solver->Settle(time, &report).ok());
    const EnergySummary e = Energy(*solver);
    EXPECT_EQ(e.kinetic, 0.0) << "every particle stops at the end of the settle";
    // The water (~4 kg) sinks by ~0.1 mm as it compresses and rearranges: the steps below are
    // millijoules, far above SphEnergy's double-precision rounding.
    EXPECT_LT(e.Total(), previous - 1e-4) << "the minimiser did not go downhill by " << time << " s";
    RecordProperty("energy_after_" + std::to_string(time) + "_s", std::to_string(e.Total()));
    previous = e.Total();
  }
}

TEST(SettleTest, RestartsTheClockWithEveryParticleAtRest) {
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(Tank(), ::sphxr::test::AllCoresConfig(), &solver).ok());
  SettleReport report;
  ASSERT_TRUE(solver->Settle(0.05, &report).ok());
  EXPECT_GE(report.time, 0.05);
  EXPECT_GT(report.steps, 10);
  EXPECT_FALSE(report.stopped);
  EXPECT_EQ(solver->Time(), 0.0);
  EXPECT_EQ(solver->GetTotals().steps, 0);
  EXPECT_EQ(solver->LastStep().maxSpeed, 0.0f);
  HostFluid fluid;
  solver->Download(&fluid);
  ASSERT_EQ(fluid.size(), 500u);
  for (const Vec4& v : fluid.velocity) ASSERT_TRUE(v.x == 0.0f && v.y == 0.0f && v.z == 0.0f);
  // The run then starts from it: its first step ends at t = dt.
  ASSERT_TRUE(solver->Step().ok());
  EXPECT_DOUBLE_EQ(solver->Time(), solver->LastStep().dt);
  EXPECT_EQ(solver->GetTotals().steps, 1);
}

TEST(SettleTest, ProgressIsReportedAndCanStopIt) {
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(Tank(), ::sphxr::test::AllCoresConfig(), &solver).ok());
  int calls = 0;
  double last = 0.0;
  SettleReport report;
  ASSERT_TRUE(solver->Settle(1.0, &report, [&](double done) {
                  EXPECT_GT(done, last);
                  last = done;
                  return ++calls < 5;
                }).ok());
  EXPECT_EQ(calls, 5);
  EXPECT_TRUE(report.stopped);
  EXPECT_EQ(report.steps, 5) << "one call per step";
  EXPECT_GT(report.time, 0.0);
  EXPECT_EQ(solver->Time(), 0.0);
}

TEST(SettleTest, RefusesBadTimesAndALateCall) {
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(Tank(), ::sphxr::test::AllCoresConfig(), &solver).ok());
  SettleReport report;
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const Status s = solver->Settle(bad, &report);
    ASSERT_FALSE(s.ok()) << bad;
    EXPECT_NE(s.message().find("positive number of seconds"), std::string::npos) << s.message();
  }
  EXPECT_EQ(solver->GetTotals().steps, 0) << "a refused settle takes no step";
  ASSERT_TRUE(solver->Step().ok());
  const Status late = solver->Settle(0.1, &report);
  ASSERT_FALSE(late.ok());
  EXPECT_NE(late.message().find("only before the first step"), std::string::npos) << late.message();
  EXPECT_EQ(solver->GetTotals().steps, 1);
}

// A state that goes non-finite while settling is an error naming the step, not minutes of NaN steps.
TEST(SettleTest, ANonFiniteStateStopsItWithAnError) {
  SceneSetup scene = Tank();
  ASSERT_TRUE(ApplyReusePreset("balanced", &scene.reuse));  // the settle turns reuse off while it runs
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(scene, ::sphxr::test::AllCoresConfig(), &solver).ok());
  HostFluid fluid;
  solver->Download(&fluid);
  fluid.velocity[17].y = std::numeric_limits<float>::quiet_NaN();
  ASSERT_TRUE(solver->Upload(fluid).ok());
  SettleReport report;
  const Status s = solver->Settle(10.0, &report);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("non-finite"), std::string::npos) << s.message();
  EXPECT_LT(solver->GetTotals().steps, 5) << "stopped at once";
  EXPECT_TRUE(solver->Scene().reuse.enabled) << "a failed settle gives the scene its reuse back";
}

}  // namespace
}  // namespace sphxr::sim
