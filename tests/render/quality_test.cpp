// --quality auto: the spacing model (simulated s per wall s ~ h^4) and the measured choice on a real solver.
#include <gtest/gtest.h>

#include <cmath>

#include "sphxr/app/quality.h"
#include "support.h"

namespace sphxr::test {
namespace {

TEST(QualityTest, SpacingScalesWithTheFourthRootOfTheSpeedRatio) {
  // Cost ~ h^-4: 16x too slow needs twice the spacing; 16x too fast allows half.
  EXPECT_NEAR(app::SpacingForRealtime(0.01f, 1.0 / 16.0, 1.0, 0.001f, 1.0f), 0.02f, 1e-6f);
  EXPECT_NEAR(app::SpacingForRealtime(0.01f, 16.0, 1.0, 0.001f, 1.0f), 0.005f, 1e-6f);
  EXPECT_NEAR(app::SpacingForRealtime(0.01f, 1.0, 1.0, 0.001f, 1.0f), 0.01f, 1e-6f);
  // Clamped to the allowed range; a failed measurement (0) takes the coarsest.
  EXPECT_FLOAT_EQ(app::SpacingForRealtime(0.01f, 1e-6, 1.0, 0.005f, 0.04f), 0.04f);
  EXPECT_FLOAT_EQ(app::SpacingForRealtime(0.01f, 1e6, 1.0, 0.005f, 0.04f), 0.005f);
  EXPECT_FLOAT_EQ(app::SpacingForRealtime(0.01f, 0.0, 1.0, 0.005f, 0.04f), 0.04f);
}

TEST(QualityTest, ChoiceIsMeasuredLoggedAndWithinTheAllowedRange) {
  LogCapture log;
  const SceneSetup scene = SmallDamBreak(0.01f);  // 900 particles: below the 2000 floor, so never coarser
  app::QualityChoice choice;
  const Status s = app::ChooseQuality(scene, TestConfig(), 1.0, 0.2, &choice);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_GE(choice.spacing, 0.005f - 1e-7f);
  EXPECT_LE(choice.spacing, 0.01f + 1e-7f);
  EXPECT_GT(choice.realtime, 0.0);
  EXPECT_FLOAT_EQ(choice.surfaceCellSize, choice.spacing);
  SceneSetup chosen = scene;
  chosen.params.spacing = choice.spacing;
  EXPECT_EQ(choice.fluid, sim::CountParticles(chosen).fluid);
  EXPECT_EQ(log.Count(std::string("quality auto: method ") + sim::SolverMethodName(choice.method) + ", spacing",
                      LogLevel::kInfo), 1)
      << log.All();
}

}  // namespace
}  // namespace sphxr::test
