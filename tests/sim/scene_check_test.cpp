// The scene check (sim/src/scene_check.cpp): scenes of many blocks are checked in linear time and still
// find an overlap, log one line rather than one per block, and a start the step cannot resolve (a block
// faster than WCSPH's sound speed or PBF's speed cap, a spacing too fine for the obstacles) is refused at
// once in one clean line.
#include <gtest/gtest.h>

#include <memory>

#include "refusal.h"
#include "sampling.h"
#include "scene_check.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr {
namespace {

using test::ExpectBriefRefusal;
using test::ExpectCleanRefusal;

// `n`^3 blocks of side 0.8 / n, on a lattice of pitch 1 / n: none overlaps another.
sim::SceneSetup ManyBlocks(int n) {
  sim::SceneSetup s = test::TankScene({0, 0, 0}, {1, 1, 1}, 0.02f);
  s.fluid.clear();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const sim::Vec3 lo{i / float(n), j / float(n), k / float(n)};
        s.fluid.push_back(test::Block(lo, lo + sim::Vec3{0.8f / n, 0.8f / n, 0.8f / n}));
      }
    }
  }
  return s;
}

TEST(SceneCheck, AHundredThousandBlocksAreCheckedInLinearTime) {
  sim::SceneSetup s = ManyBlocks(47);  // 103,823 blocks
  s.fluid.resize(100000);
  // Sorted, the check takes a fraction of a second; a pairwise check is quadratic, tens of seconds at
  // this count. The bound is 10x the sorted time, far below the quadratic time on any machine that runs
  // these tests.
  Status status;
  const double seconds = test::Seconds([&] { status = sim::ValidateScene(s); });
  EXPECT_TRUE(status.ok()) << status.message();
  EXPECT_LT(seconds, 10.0);
  // An overlap is still found, between the first block and the last.
  s.fluid.back() = test::Block({0.001f, 0.001f, 0.001f}, {0.5f, 0.5f, 0.5f});
  ExpectCleanRefusal(sim::ValidateScene(s), "overlaps fluid[0]");
}

TEST(SceneCheck, OverlapsAreFoundWhateverTheOrder) {
  // Two long slabs crossing, among blocks that touch: the sort must not hide the pair.
  sim::SceneSetup s = test::TankScene({0, 0, 0}, {1, 1, 1}, 0.02f);
  s.fluid = {test::Block({0, 0, 0}, {0.5f, 0.5f, 0.5f}), test::Block({0.5f, 0, 0}, {1, 0.5f, 0.5f}),
             test::Block({0, 0.5f, 0}, {1, 0.6f, 0.1f}), test::Block({0.4f, 0.5f, 0}, {0.45f, 1, 0.1f})};
  ExpectCleanRefusal(sim::ValidateScene(s), "fluid[3]");
  s.fluid.pop_back();
  EXPECT_TRUE(sim::ValidateScene(s).ok()) << "blocks that touch";
  // Less than half a spacing of overlap is rounding.
  s.fluid.push_back(test::Block({0, 0.595f, 0}, {1, 0.7f, 0.1f}));
  EXPECT_TRUE(sim::ValidateScene(s).ok());
}

TEST(SceneCheck, ManyBlocksLogOneLineNotOnePerBlock) {
  // Not a cut-block line and a thin-block warning for each block (two lines a block).
  const sim::SceneSetup s = ManyBlocks(20);  // 8,000 blocks of 0.04 m at spacing 0.02: thin and cut
  test::LogCapture log;
  sim::LogCutBlocks(s);
  sim::WarnAboutSettings(s, 8000, 100.0f);
  EXPECT_LE(log.Messages().size(), 3u) << log.All().substr(0, 2000);
}

TEST(SceneCheck, ABlockFasterThanTheSoundSpeedIsRefusedUnderWcsph) {
  // At 1,000 m/s (67x the sound speed) the step cannot resolve the start: the block blows up in a few steps.
  sim::SceneSetup s = test::SmallDamBreak(0.02f);
  s.fluid[0].velocity = {1000.0f, 0.0f, 0.0f};
  s.method = sim::SolverMethod::kWcsph;
  ExpectCleanRefusal(sim::ValidateScene(s), "sound speed");
  s.fluid[0].velocity = {0.5f, 0.0f, 0.0f};
  EXPECT_TRUE(sim::ValidateScene(s).ok());
  // DFSPH and PBF are not bound by the sound speed (solver_table.h: acoustic).
  s.fluid[0].velocity = {100.0f, 0.0f, 0.0f};
  s.method = sim::SolverMethod::kDfsph;
  EXPECT_TRUE(sim::ValidateScene(s).ok());
  // PBF holds every speed to pbf_max_speed (20 m/s): a faster block would start slower than the scene
  // says, silently.
  s.method = sim::SolverMethod::kPbf;
  ExpectCleanRefusal(sim::ValidateScene(s), "pbf_max_speed");
  s.fluid[0].velocity = {15.0f, 0.0f, 0.0f};
  EXPECT_TRUE(sim::ValidateScene(s).ok());
}

// With an obstacle, counting the particles would walk a lattice of 1.7e9 sites: refused from its bound first.
TEST(SceneCheck, ATinySpacingWithObstaclesIsRefusedAtOnce) {
  sim::SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.25f, 0.3f}, 0.0002f);
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.15f, 0.3f}));
  scene.obstacles.push_back(test::Box({0.1f, 0, 0.1f}, {0.2f, 0.05f, 0.2f}));
  std::unique_ptr<sim::Solver> solver;
  Status s;
  const double seconds = test::Seconds([&] { s = sim::Solver::Create(scene, test::TestConfig(), &solver); });
  ExpectBriefRefusal(s, "up to");
  EXPECT_LT(seconds, 1.0);
}

}  // namespace
}  // namespace sphxr
