#pragma once
// Two runs of one scene compared bit for bit: across thread counts (the CPU backend gathers per particle
// in a fixed order, sorts stably and reduces the time step by max, so the team's size changes no bit),
// and across a restore (Solver::Restore continues the saved run's own steps). Used by the conformance
// suite over the solver table's rows (tests/sim/solvers/conformance_test.cpp) and by the tests of the
// options that change the step's lists (WCSPH's reuse, the CPU's density blocks, the restored idle counts).
//
// SolverConfig::threads sets the OpenMP team, which is process-global, so each solver is created and run
// to the end before the next one is created.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "backend.h"  // sim/src: UsePairDensityBlocks
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim::same_bits {

struct RunResult {
  HostFluid fluid;
  std::vector<float> dts;
  double meanComputed = 0;  // the mean fraction of particles that computed per step
};

inline RunResult RunScene(const SceneSetup& scene, int threads, int steps, bool pairDensityBlocks = false) {
  SolverConfig config = ::sphxr::test::TestConfig();
  config.threads = threads;
  RunResult run;
  auto solver = ::sphxr::test::CreateOrFail(scene, config);
  if (!solver) return run;
  if (pairDensityBlocks) solver->BackendForTests()->UsePairDensityBlocks();
  EXPECT_EQ(omp_get_max_threads(), threads) << "SolverConfig.threads did not reach the OpenMP runtime";
  for (int s = 0; s < steps; ++s) {
    const Status st = solver->Step();
    if (!st.ok()) {
      ADD_FAILURE() << "threads " << threads << ", step " << s + 1 << ": " << st.message();
      return run;
    }
    run.dts.push_back(solver->LastStep().dt);
    run.meanComputed += solver->LastStep().activeFraction / steps;
  }
  solver->Download(&run.fluid);
  return run;
}

inline bool SameBits(const Vec4& a, const Vec4& b) { return std::memcmp(&a, &b, 3 * sizeof(float)) == 0; }

/// Compares two runs of test::SmallDamBreak(0.01f) bit for bit (by particle id), after checking that the
/// flow moved.
inline void ExpectIdentical(const RunResult& one, const RunResult& two) {
  ASSERT_EQ(one.fluid.size(), 900u);
  ASSERT_EQ(two.fluid.size(), one.fluid.size());
  ASSERT_EQ(::sphxr::test::FirstNonFinite(one.fluid), "");

  for (size_t s = 0; s < one.dts.size(); ++s) {
    ASSERT_EQ(one.dts[s], two.dts[s]) << "time step " << s + 1 << " differs";
  }
  // The flow actually moved (otherwise identical results prove nothing).
  double moved = 0;
  for (const Vec4& v : one.fluid.velocity) moved = std::max(moved, static_cast<double>(std::abs(v.x)));
  EXPECT_GT(moved, 0.1) << "the column should be spreading after 200 steps";

  const auto byId = ::sphxr::test::IndexById(two.fluid);
  int positionDiffs = 0, velocityDiffs = 0, orderDiffs = 0;
  for (size_t i = 0; i < one.fluid.size(); ++i) {
    const auto it = byId.find(one.fluid.id[i]);
    ASSERT_NE(it, byId.end()) << "id " << one.fluid.id[i] << " missing in the 2-thread run";
    const size_t j = it->second;
    orderDiffs += (i != j);
    if (!SameBits(one.fluid.position[i], two.fluid.position[j]) && positionDiffs++ < 5) {
      ADD_FAILURE() << "position of id " << one.fluid.id[i] << " differs: [" << one.fluid.position[i].x << ", "
                    << one.fluid.position[i].y << ", " << one.fluid.position[i].z << "] vs ["
                    << two.fluid.position[j].x << ", " << two.fluid.position[j].y << ", " << two.fluid.position[j].z
                    << "]";
    }
    if (!SameBits(one.fluid.velocity[i], two.fluid.velocity[j]) && velocityDiffs++ < 5) {
      ADD_FAILURE() << "velocity of id " << one.fluid.id[i] << " differs";
    }
  }
  EXPECT_EQ(positionDiffs, 0);
  EXPECT_EQ(velocityDiffs, 0);
  EXPECT_EQ(orderDiffs, 0) << "the sorted order differs between thread counts";
}

/// Steps `solver` `steps` times and returns every step's dt.
inline std::vector<float> Run(Solver* solver, int steps) {
  std::vector<float> dts;
  for (int k = 0; k < steps; ++k) {
    EXPECT_TRUE(solver->Step().ok());
    dts.push_back(solver->LastStep().dt);
  }
  return dts;
}

/// The truth is the solver that was never stopped: the scene saved mid-run and restored into a fresh
/// solver of the same scene must take the same steps, bit for bit, with reuse's idle counts carried along.
inline void ExpectRestoredRunMatches(const SceneSetup& scene) {
  // The one that runs through: 60 steps, saved after 40 (the column is falling and spreading).
  auto through = ::sphxr::test::CreateOrFail(scene);
  ASSERT_TRUE(through);
  Run(through.get(), 40);
  HostFluid saved;
  through->Download(&saved);
  const SolverClock clock = through->Clock();
  EXPECT_GT(clock.time, 0.0);
  EXPECT_GT(clock.lastMaxSpeed, 0.1f) << "the column should be moving when it is saved";
  const std::vector<float> throughDts = Run(through.get(), 20);

  auto restored = ::sphxr::test::CreateOrFail(scene);
  ASSERT_TRUE(restored);
  ASSERT_TRUE(restored->Restore(saved, clock).ok());
  EXPECT_EQ(restored->Time(), clock.time);
  const std::vector<float> restoredDts = Run(restored.get(), 20);
  EXPECT_EQ(restoredDts, throughDts) << "the time steps after the restart differ";
  EXPECT_EQ(restored->Time(), through->Time());
  EXPECT_EQ(restored->GetTotals().steps, 20) << "the step count starts at 0 after a restore";

  HostFluid a, b;
  through->Download(&a);
  restored->Download(&b);
  ASSERT_EQ(a.size(), b.size());
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const bool same = a.id[i] == b.id[i] && std::memcmp(&a.position[i], &b.position[i], sizeof(Vec4)) == 0 &&
                      std::memcmp(&a.velocity[i], &b.velocity[i], sizeof(Vec4)) == 0 && a.density[i] == b.density[i] &&
                      a.idle[i] == b.idle[i];
    if (!same && differ++ < 5) {
      ADD_FAILURE() << "particle " << i << " (id " << a.id[i] << " / " << b.id[i] << ") differs after the restart: x "
                    << a.position[i].x << " / " << b.position[i].x << ", v " << a.velocity[i].x << " / "
                    << b.velocity[i].x;
    }
  }
  EXPECT_EQ(differ, 0);
}

}  // namespace sphxr::sim::same_bits
