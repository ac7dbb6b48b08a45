// The CPU backend is deterministic across thread counts and schedules: per-particle gathers in a fixed
// order, a stable sort and max reductions for the time step. Its SIMD stages hand out guided chunks, so
// which thread takes which particles may change from run to run (backend_cpu.cpp). The same scene on 1,
// 2 (twice) and 3 threads must give bit-identical positions and velocities, with reuse off; on 1 and 2
// with reuse on (its compacted list); and the CPU density blocks' two layouts alike. All in this process:
// SolverConfig::threads sets the OpenMP team, which is process-global, so each solver is created and run
// to the end before the next one is created. ctest runs it with OMP_WAIT_POLICY=passive
// (tests/CMakeLists.txt): with libgomp's default active waiting, a 2-thread team on a 2-core machine that
// another process also uses spins at every barrier and the test takes 30-45 s instead of a few.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <string>
#include <vector>

#include "backend.h"  // sim/src: UsePairDensityBlocks
#include "support.h"

namespace sphxr::sim {
namespace {

struct RunResult {
  HostFluid fluid;
  std::vector<float> dts;
  double meanComputed = 0;  // the mean fraction of particles that computed per step
};

RunResult RunScene(const SceneSetup& scene, int threads, int steps, bool pairDensityBlocks = false) {
  SolverConfig config = test::TestConfig();
  config.threads = threads;
  RunResult run;
  auto solver = test::CreateOrFail(scene, config);
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

bool SameBits(const Vec4& a, const Vec4& b) { return std::memcmp(&a, &b, 3 * sizeof(float)) == 0; }

/// Compares two runs bit for bit (by particle id), after checking that the flow moved.
void ExpectIdentical(const RunResult& one, const RunResult& two) {
  ASSERT_EQ(one.fluid.size(), 900u);
  ASSERT_EQ(two.fluid.size(), one.fluid.size());
  ASSERT_EQ(test::FirstNonFinite(one.fluid), "");

  for (size_t s = 0; s < one.dts.size(); ++s) {
    ASSERT_EQ(one.dts[s], two.dts[s]) << "time step " << s + 1 << " differs";
  }
  // The flow actually moved (otherwise identical results prove nothing).
  double moved = 0;
  for (const Vec4& v : one.fluid.velocity) moved = std::max(moved, static_cast<double>(std::abs(v.x)));
  EXPECT_GT(moved, 0.1) << "the column should be spreading after 200 steps";

  const auto byId = test::IndexById(two.fluid);
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

// A small dam break: 10 x 15 x 6 = 900 particles, 200 steps (the column is falling and spreading).
TEST(DeterminismTest, OneAndTwoThreadsGiveIdenticalResults) {
  const SceneSetup scene = test::SmallDamBreak(0.01f);
  const RunResult one = RunScene(scene, 1, 200);
  {
    SCOPED_TRACE("1 and 2 threads");
    ExpectIdentical(one, RunScene(scene, 2, 200));
  }
  {
    SCOPED_TRACE("1 and 2 threads, again (the guided chunks may split otherwise)");
    ExpectIdentical(one, RunScene(scene, 2, 200));
  }
  {
    SCOPED_TRACE("1 and 3 threads (other chunks for certain)");
    ExpectIdentical(one, RunScene(scene, 3, 200));
  }
}

// With reuse the density and force stages run over the compacted list of computing particles (`balanced`;
// its still column reuses at the start).
TEST(DeterminismTest, OneAndTwoThreadsGiveIdenticalResultsWithReuse) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  ASSERT_TRUE(ApplyReusePreset("balanced", &scene.reuse));
  const RunResult one = RunScene(scene, 1, 200);
  EXPECT_LT(one.meanComputed, 0.99) << "some particles should reuse, or the list is the identity";
  ExpectIdentical(one, RunScene(scene, 2, 200));
}

// The CPU's density blocks fitted to the particles (boxes of up to 4 x 4 x 4 cells in the spreading front,
// crowded pairs cut per cell) change no bit against the pairs-only layout (Backend::UsePairDensityBlocks,
// which sphxr_bench_blocks times against them), with reuse off and on. tests/sim/cpu_stages_test.cpp
// checks the same for one density pass per layout on made-up particles; this runs the whole solver.
TEST(DeterminismTest, DensityBlocksFittedToTheParticlesGiveThePairsBits) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  {
    SCOPED_TRACE("reuse off");
    ExpectIdentical(RunScene(scene, 2, 200), RunScene(scene, 2, 200, true));
  }
  ASSERT_TRUE(ApplyReusePreset("balanced", &scene.reuse));
  {
    SCOPED_TRACE("reuse balanced");
    const RunResult fitted = RunScene(scene, 2, 200);
    EXPECT_LT(fitted.meanComputed, 0.99) << "some particles should reuse, or the blocks of the computing ones are all";
    ExpectIdentical(fitted, RunScene(scene, 2, 200, true));
  }
}

}  // namespace
}  // namespace sphxr::sim
