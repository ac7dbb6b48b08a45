// Solver::DownloadBoundary hands out every per-wall-particle field the walls carry, in the solver's sorted
// order, the walls' inverse reference (tank.wall_pressure = "wall_density") included: the energy audit
// (bench/rest.cpp --energy, sim/measure.h SphEnergy) reads it.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "kernel.h"
#include "sampling.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

SceneSetup SmallTank(SceneSetup::WallPressure walls) {
  SceneSetup s;
  s.params.spacing = 0.02f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.2f, 0.3f, 0.12f}};
  s.fluid.push_back(FluidBlock{{{0.0f, 0.0f, 0.0f}, {0.2f, 0.16f, 0.12f}}, {}});
  s.wallPressure = walls;
  return s;
}

TEST(BoundaryDownload, WallDensityReferencesFollowTheSortedPositions) {
  const SceneSetup scene = SmallTank(SceneSetup::WallPressure::kWallDensity);
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(scene, ::sphxr::test::AllCoresConfig(), &solver).ok());
  HostBoundary b;
  solver->DownloadBoundary(&b);
  ASSERT_EQ(b.invReference.size(), b.size());
  ASSERT_GT(b.size(), 0u);
  // Each downloaded reference is the one computed for the position it came with: recomputed here from
  // that position alone (the sampler's own function, floored at a quarter of the flat wall's, as the
  // solver does), so a gather in the wrong order or a stale copy would show.
  const CubicSpline kernel = CubicSpline::Make(scene.params.spacing * scene.params.supportFactor);
  int seeing = 0;
  for (size_t i = 0; i < b.size(); ++i) {
    const std::vector<float> one = WallInverseReferences(scene, kernel, {b.position[i]}, 0.25f);
    EXPECT_FLOAT_EQ(b.invReference[i], one[0]) << "wall particle " << i;
    // A floor particle under the middle of the water sees the flat wall's fluid: 1 / WallFluidSum.
    if (b.invReference[i] > 0.0f && b.invReference[i] < 1.01f / WallFluidSum(kernel, scene.params.spacing)) ++seeing;
  }
  EXPECT_GT(seeing, 0) << "no wall particle sees a flat wall's worth of fluid";
}

TEST(BoundaryDownload, MirroredWallsHaveNoReferences) {
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(SmallTank(SceneSetup::WallPressure::kMirrored), ::sphxr::test::AllCoresConfig(), &solver).ok());
  HostBoundary b;
  solver->DownloadBoundary(&b);
  EXPECT_GT(b.size(), 0u);
  EXPECT_TRUE(b.invReference.empty());
}

}  // namespace
}  // namespace sphxr::sim
