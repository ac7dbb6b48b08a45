// TeamSizer (sim/src/cpu/team.h): the CPU backend's team chosen from the steps' durations. Fed the step
// times of the contention benchmark's table (bench/results/contention.csv: stir on 2 cores, alone 2
// threads 7.2 ms and 1 thread 12.5 ms; beside a busy process 17.8 and 13.0 ms), with +-10 % noise, it
// must settle on the faster team, spend few steps trying the other, and follow a neighbour that comes
// and goes. Whatever the team, the bits are the same (solvers/conformance_test.cpp, every row); only
// the speed is at stake.
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "cpu/team.h"

namespace sphxr::sim {
namespace {

struct Tally {
  int steps = 0, atCores = 0, changes = 0;
  double seconds = 0.0;
};

/// `steps` steps of a sizer whose step at `threads` takes time(step, threads) seconds, +-10 %.
Tally Drive(TeamSizer& team, int steps, const std::function<double(int, int)>& time, unsigned seed = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(0.9, 1.1);
  Tally r;
  int last = team.Threads();
  for (int s = 0; s < steps; ++s) {
    const int t = team.Threads();
    if (t != last) ++r.changes, last = t;
    if (t == team.Sizes().front()) ++r.atCores;
    const double dt = time(s, t) * noise(rng);
    r.seconds += dt;
    team.Record(dt);
    ++r.steps;
  }
  return r;
}

double Alone(int, int threads) { return threads == 2 ? 7.2e-3 : 12.5e-3; }
double Busy(int, int threads) { return threads == 2 ? 17.8e-3 : 13.0e-3; }

TEST(TeamSizer, AloneKeepsEveryCoreAndTriesTheOtherTeamRarely) {
  TeamSizer team(2, true);
  const Tally r = Drive(team, 5000, Alone);
  EXPECT_EQ(team.Threads(), 2);
  // tries after 64, 256, 1024, 4096 steps: at most 4 windows at 1 thread
  EXPECT_LE(r.steps - r.atCores, 4 * TeamSizer::kWindow);
  // the cost of trying: within 3 % of all steps at 2 threads
  EXPECT_LT(r.seconds, 1.03 * 5000 * 7.2e-3);
}

TEST(TeamSizer, BesideABusyProcessOneThreadWins) {
  TeamSizer team(2, true);
  const Tally r = Drive(team, 5000, Busy);
  EXPECT_EQ(team.Threads(), 1);
  // the first try comes after kMinInterval steps; then 2 threads only for confirming windows
  EXPECT_LE(r.atCores, TeamSizer::kMinInterval + 2 * TeamSizer::kWindow + 8 * TeamSizer::kWindow);
  EXPECT_LT(r.seconds, 1.3 * 5000 * 12.5e-3) << "the bound: 1.3x one thread alone";
}

TEST(TeamSizer, FollowsANeighbourThatComesAndGoes) {
  TeamSizer team(2, true);
  // alone for 2000 steps, a busy neighbour for 2000, alone again for 6000
  auto time = [](int s, int t) { return s >= 2000 && s < 4000 ? Busy(s, t) : Alone(s, t); };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> noise(0.9, 1.1);
  int firstAtOne = -1, backAtTwo = -1;
  for (int s = 0; s < 10000; ++s) {
    const int t = team.Threads();
    if (s >= 2000 && firstAtOne < 0 && t == 1) firstAtOne = s;
    if (s >= 4000 && backAtTwo < 0 && t == 2) backAtTwo = s;
    team.Record(time(s, t) * noise(rng));
  }
  // the rise by more than half (17.8 against 7.2 ms) tries at once: one window to see it, one to try
  ASSERT_GE(firstAtOne, 2000);
  EXPECT_LE(firstAtOne - 2000, 3 * TeamSizer::kWindow);
  // leaving shows no rise (1 thread alone is no slower), so the next scheduled try finds it
  ASSERT_GE(backAtTwo, 4000);
  EXPECT_LE(backAtTwo - 4000, TeamSizer::kMaxInterval + 2 * TeamSizer::kWindow);
  EXPECT_EQ(team.Threads(), 2);
}

TEST(TeamSizer, AGivenThreadCountIsKept) {
  TeamSizer team(2, false);
  const Tally r = Drive(team, 1000, Busy);
  EXPECT_EQ(r.atCores, 1000);
  EXPECT_EQ(r.changes, 0);
  TeamSizer one(1, true);
  EXPECT_EQ(Drive(one, 200, Alone).changes, 0);
}

TEST(TeamSizer, ALadderOfHalvesFindsTheFastestTeam) {
  TeamSizer team(16, true);
  ASSERT_EQ(team.Sizes(), (std::vector<int>{16, 8, 4, 2, 1}));
  // a 16-core machine with several busy neighbours: 8 threads fastest, 16 collapsed
  auto time = [](int, int t) {
    switch (t) {
      case 16: return 40e-3;
      case 8: return 2.0e-3;
      case 4: return 3.0e-3;
      case 2: return 5.5e-3;
      default: return 10e-3;
    }
  };
  Drive(team, 3000, time);
  EXPECT_EQ(team.Threads(), 8);
}

}  // namespace
}  // namespace sphxr::sim
