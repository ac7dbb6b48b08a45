// Solver::Restore: a restart from a saved state (the state file of app/src/state_file.h). The truth is
// the solver that was never stopped: a small dam break saved mid-collapse and restored into a fresh
// solver of the same scene must take the same steps, bit for bit (the CPU backend is deterministic).
// That every solver does is the conformance suite's case (tests/sim/solvers/conformance_test.cpp); here
// reuse's idle counts carried along, and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "sim/same_bits.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

using same_bits::ExpectRestoredRunMatches;

TEST(Restore, CarriesReuseIdleCounts) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  ASSERT_TRUE(ApplyReusePreset("balanced", &scene.reuse));
  scene.reuse.enabled = true;
  ExpectRestoredRunMatches(scene);
}

TEST(Restore, IdleCountsBeyondThisRunsIdleStartActive) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  ASSERT_TRUE(ApplyReusePreset("fast", &scene.reuse));  // IDLE 3
  scene.reuse.enabled = true;
  auto saved = test::CreateOrFail(scene);
  ASSERT_TRUE(saved);
  HostFluid fluid;
  int longest = -1;
  for (int k = 0; k < 40 && longest <= 1; ++k) {  // until some particle has an idle count above 1
    ASSERT_TRUE(saved->Step().ok());
    saved->Download(&fluid);
    for (int32_t ic : fluid.idle) longest = std::max(longest, static_cast<int>(ic));
  }
  ASSERT_GT(longest, 1) << "the fast preset should have set idle counts above 1 in a falling column";

  scene.reuse.idle = 1;
  auto restored = test::CreateOrFail(scene);
  ASSERT_TRUE(restored);
  ASSERT_TRUE(restored->Restore(fluid, saved->Clock()).ok());
  HostFluid back;
  restored->Download(&back);
  for (size_t i = 0; i < back.size(); ++i) {
    ASSERT_LE(back.idle[i], 1) << "particle " << i << " would reuse longer than this run's IDLE";
    ASSERT_GE(back.idle[i], -3) << "particle " << i;
  }
}

TEST(Restore, RefusesWhatCannotBeTheSameScene) {
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f));
  ASSERT_TRUE(solver);
  HostFluid fluid;
  solver->Download(&fluid);
  SolverClock clock;

  HostFluid fewer = fluid;
  fewer.resize(fluid.size() - 1);
  Status s = solver->Restore(fewer, clock);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("particles"), std::string::npos) << s.message();

  HostFluid nan = fluid;
  nan.position[7].y = std::numeric_limits<float>::quiet_NaN();
  s = solver->Restore(nan, clock);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("non-finite"), std::string::npos) << s.message();

  // A restored idle particle's neighbours divide by its density and read its pressure term.
  HostFluid empty = fluid;
  empty.density[3] = 0.0f;
  s = solver->Restore(empty, clock);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("density that is not a positive number"), std::string::npos) << s.message();
  HostFluid term = fluid;
  term.pressureTerm[5] = std::numeric_limits<float>::infinity();
  s = solver->Restore(term, clock);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("pressure term"), std::string::npos) << s.message();

  SolverClock bad;
  bad.time = -1.0;
  EXPECT_FALSE(solver->Restore(fluid, bad).ok());
  bad.time = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(solver->Restore(fluid, bad).ok());
  bad.time = 1e18;  // a flipped exponent bit: no step moves such a clock, and it hung the headless runner
  s = solver->Restore(fluid, bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("at most 1e9 s"), std::string::npos) << s.message();

  ASSERT_TRUE(solver->Step().ok());
  s = solver->Restore(fluid, clock);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("before the first step"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace sphxr::sim
