// --quality auto: the spacing model (simulated s per wall s ~ h^4) and the measured choice on a real solver.
#include <gtest/gtest.h>

#include <cmath>

#include "solvers/pbf/pbf_rules.h"
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
  if (choice.method == sim::SolverMethod::kPbf) {
    EXPECT_EQ(choice.params.pbfSubsteps, sim::PbfSubstepsForSpacing(scene.params.pbfSubsteps, 0.01f, choice.spacing));
  } else {
    EXPECT_EQ(choice.params.pbfSubsteps, scene.params.pbfSubsteps);
  }
  EXPECT_EQ(log.Count(std::string("quality auto: method ") + sim::SolverMethodName(choice.method) + ", spacing",
                      LogLevel::kInfo), 1)
      << log.All();
}

TEST(QualityTest, PbfSubstepsKeepTheScenesStepPerSpacing) {
  // The fewest substeps with dt / h at most the scene's (3 at 1 cm).
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.01f), 3.0f);
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.015f), 2.0f);  // 3 x 2/3 exactly, despite rounding
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.0177f), 2.0f);
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.03f), 1.0f);
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.1f), 1.0f);
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.005f), 6.0f);
  EXPECT_EQ(sim::PbfSubstepsForSpacing(3.0f, 0.01f, 0.001f), 16.0f);  // pbf_substeps' largest
}

/// PBF still water (PbfStillWater) at `spacing` and `substeps`, 1 s from the lattice: its mean
/// compression at the end.
float PbfStillWaterCompression(float spacing, float substeps) {
  SceneSetup s = PbfStillWater(spacing);
  s.params.pbfSubsteps = substeps;
  auto solver = CreateOrFail(s);
  if (!solver) return -1.0f;
  while (solver->Time() < 1.0 - 1e-9) {
    if (!solver->Step().ok()) return -1.0f;
  }
  if (FirstNonFinite(DownloadFluid(*solver)) != "") return -1.0f;
  return solver->LastStep().meanDensityError;
}

TEST(QualityTest, FewerPbfSubstepsAtACoarserSpacingKeepTheScenesCompression) {
  // PBF's rest compression goes as g D dt^2 / (N h^2): at the same dt / h a coarser lattice holds the
  // same column no more compressed, and stays stable (2 substeps at 1.5 cm, 1 at 3 cm, against 3 at 1 cm).
  const float reference = PbfStillWaterCompression(0.01f, 3.0f);
  ASSERT_GT(reference, 0.0f);
  for (const float h : {0.015f, 0.03f}) {
    const float c = PbfStillWaterCompression(h, sim::PbfSubstepsForSpacing(3.0f, 0.01f, h));
    ASSERT_GE(c, 0.0f) << "unstable at " << h << " m";
    EXPECT_LE(c, reference) << "at " << h << " m";
  }
}

}  // namespace
}  // namespace sphxr::test
