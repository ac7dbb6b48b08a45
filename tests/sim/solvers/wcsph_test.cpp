// WCSPH (sim/src/solvers/wcsph.h, Becker & Teschner 2007): its options keep the CPU backend's bits at
// every thread count, as its plain step does (tests/sim/solvers/conformance_test.cpp, every row). With
// reuse (activity-based reuse, WCSPH's alone in the solver table) the density and force stages run over
// the compacted list of computing particles; the CPU's density blocks fitted to the particles change no
// bit against the pairs-only layout. ctest runs it with OMP_WAIT_POLICY=passive (tests/CMakeLists.txt):
// with libgomp's default active waiting, a 2-thread team on a 2-core machine that another process also
// uses spins at every barrier and the test takes 30-45 s instead of a few.
#include <gtest/gtest.h>

#include "sim/same_bits.h"
#include "support.h"

namespace sphxr::sim {
namespace {

using same_bits::ExpectIdentical;
using same_bits::RunResult;
using same_bits::RunScene;

// With reuse the density and force stages run over the compacted list of computing particles (`balanced`;
// its still column reuses at the start).
TEST(Wcsph, OneAndTwoThreadsGiveIdenticalResultsWithReuse) {
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
TEST(Wcsph, DensityBlocksFittedToTheParticlesGiveThePairsBits) {
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
