// The benchmark dam break (scenes/dam_break_1m.json: 50,653 particles, a 1 m column thrown across a 4 m
// tank, up the far wall and back) held by its walls for the scene's whole run: the clamp behind them
// (a quarter spacing in front of each face) catches fewer than 1 in 10,000 particle-steps
// (sim::kLeakingClampRate, where it is a safety net; docs/design/walls.md). The Martin & Moyce scene's
// rate is checked in dam_break_test.cpp, a jet at a wall and an obstacle in tests/sim/walls_clamp_test.cpp.
// The same bound under DFSPH, whose walls are its density solve and the contact on water lighter than
// rho0 (docs/design/dfsph.md).
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "sphxr/app/scene_file.h"
#include "sphxr/sim/solver.h"

namespace sphxr {
namespace {

class WallsHold : public ::testing::TestWithParam<const char*> {};

TEST_P(WallsHold, TheBenchmarkDamBreakIsHeldByItsWalls) {
  app::SceneFile scene;
  ASSERT_TRUE(app::LoadScene(SPHXR_SCENES_DIR "/dam_break_1m.json", &scene).ok());
  ASSERT_TRUE(sim::ParseSolverMethod(GetParam(), &scene.setup.method));
  ASSERT_GT(scene.runTime, 1.5) << "past the impact on the far wall and the run-up";
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(scene.setup, sim::SolverConfig{}, &solver).ok());
  const int n = solver->FluidCount();
  while (solver->Time() < scene.runTime) ASSERT_TRUE(solver->Step().ok()) << "at t = " << solver->Time();
  const sim::Totals& totals = solver->GetTotals();
  EXPECT_EQ(totals.particleSteps, static_cast<int64_t>(n) * totals.steps);
  const double rate = static_cast<double>(totals.clampedEvents) / static_cast<double>(totals.particleSteps);
  RecordProperty("clamps_per_thousand", std::to_string(1e3 * rate));
  EXPECT_LT(rate, sim::kLeakingClampRate) << totals.clampedEvents << " clamps in " << totals.particleSteps
                                          << " particle-steps";
}

INSTANTIATE_TEST_SUITE_P(Method, WallsHold, ::testing::Values("wcsph", "dfsph"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

}  // namespace
}  // namespace sphxr
