// The render budget (app/include/sphxr/app/render_budget.h): frames that do not fit lower the render
// quality one level per window of frames, frames that fit never do, a fixed quality never moves; and
// the --frame-stats CSV: a header from the passes, one whole row per frame, nothing partial on a full disk.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "sphxr/app/quality.h"
#include "sphxr/app/render_budget.h"
#include "support.h"

namespace sphxr::test {
namespace {

using app::RenderBudget;
using render::RenderQuality;

TEST(RenderBudget, FramesThatDoNotFitLowerTheQualityOneLevelPerWindow) {
  RenderBudget budget(RenderQuality::kHigh, /*adaptive=*/true);
  const double period = 1000.0 / 90.0;
  int lowered = 0;
  for (int f = 0; f < RenderBudget::kWindow - 1; ++f) lowered += budget.Observe(2.0 * period, period);
  EXPECT_EQ(lowered, 0) << "a window is judged when it is full";
  EXPECT_TRUE(budget.Observe(2.0 * period, period));
  EXPECT_EQ(budget.Quality(), RenderQuality::kMedium);
  EXPECT_NE(budget.Why().find("high -> medium"), std::string::npos) << budget.Why();
  for (int f = 0; f < RenderBudget::kWindow; ++f) budget.Observe(2.0 * period, period);
  EXPECT_EQ(budget.Quality(), RenderQuality::kLow);
  for (int f = 0; f < 3 * RenderBudget::kWindow; ++f) EXPECT_FALSE(budget.Observe(2.0 * period, period));
  EXPECT_EQ(budget.Quality(), RenderQuality::kLow) << "low is the floor";
}

TEST(RenderBudget, FramesThatFitOrAFixedQualityNeverMove) {
  const double period = 1000.0 / 90.0;
  RenderBudget fits(RenderQuality::kHigh, true);
  // A few slow frames (under half the window) among frames that fit: the median fits.
  for (int f = 0; f < 10 * RenderBudget::kWindow; ++f) EXPECT_FALSE(fits.Observe(f % 3 == 0 ? 5.0 * period : 0.9 * period, period));
  EXPECT_EQ(fits.Quality(), RenderQuality::kHigh);
  RenderBudget fixed(RenderQuality::kHigh, /*adaptive=*/false);
  for (int f = 0; f < 10 * RenderBudget::kWindow; ++f) EXPECT_FALSE(fixed.Observe(10.0 * period, period));
  EXPECT_EQ(fixed.Quality(), RenderQuality::kHigh);
  RenderBudget nonsense(RenderQuality::kHigh, true);  // a zero or non-finite interval is not a frame
  for (int f = 0; f < 3 * RenderBudget::kWindow; ++f) EXPECT_FALSE(nonsense.Observe(f % 2 ? 0.0 : std::nan(""), period));
}

render::DrawStats Stats(double shadow, double water) {
  render::DrawStats s;
  s.views = 2;
  s.passes = {{"shadow", shadow}, {"water thickness", water}};
  return s;
}

TEST(FrameStatsCsv, AHeaderFromThePassesThenOneRowPerFrame) {
  TempDir dir("frame_stats");
  const std::string path = dir.File("frames.csv");
  {
    app::FrameStatsCsv csv;
    ASSERT_TRUE(csv.Open(path).ok());
    ASSERT_TRUE(csv.Append(0, 11.0, RenderQuality::kHigh, render::DrawStats{}).ok());  // no pass timed yet: no row
    ASSERT_TRUE(csv.Append(1, 11.5, RenderQuality::kHigh, Stats(0.5, 0.25)).ok());
    ASSERT_TRUE(csv.Append(2, 12.5, RenderQuality::kMedium, Stats(0.25, 0.125)).ok());
  }
  std::ifstream in(path);
  std::string header, row1, row2, extra;
  ASSERT_TRUE(std::getline(in, header));
  ASSERT_TRUE(std::getline(in, row1));
  ASSERT_TRUE(std::getline(in, row2));
  EXPECT_FALSE(std::getline(in, extra));
  EXPECT_EQ(header, "frame,interval_ms,render_quality,views,gpu_ms,gpu_shadow_ms,gpu_water_thickness_ms");
  EXPECT_EQ(row1, "1,11.500,high,2,0.7500,0.5000,0.2500");
  EXPECT_EQ(row2, "2,12.500,medium,2,0.3750,0.2500,0.1250");
}

TEST(FrameStatsCsv, AFolderThatCannotBeWrittenAndAFullDiskAreOneLine) {
  app::FrameStatsCsv csv;
  const Status s = csv.Open("/nonexistent-folder/frames.csv");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
  EXPECT_NE(s.message().find("/nonexistent-folder/frames.csv"), std::string::npos);
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  app::FrameStatsCsv full;
  ASSERT_TRUE(full.Open("/dev/full").ok());
  const Status w = full.Append(1, 11.0, RenderQuality::kHigh, Stats(0.5, 0.25));
  EXPECT_FALSE(w.ok());
  EXPECT_NE(w.message().find("write failed"), std::string::npos) << w.message();
  EXPECT_FALSE(full.IsOpen());
  EXPECT_TRUE(full.Append(2, 11.0, RenderQuality::kHigh, Stats(0.5, 0.25)).ok()) << "stopped: later rows are dropped quietly";
}

TEST(RenderSummary, NamesTheQualityAndEachPassPerView) {
  EXPECT_EQ(app::RenderSummary(RenderQuality::kLow, render::DrawStats{}), "render quality low");
  EXPECT_EQ(app::RenderSummary(RenderQuality::kHigh, Stats(0.5, 0.25)),
            "render quality high; GPU per view 0.38 ms: shadow 0.25, water thickness 0.12");
}

TEST(QualityAuto, TurnsSprayFoamAndBubblesOffOnlyWhenTheWaterCannotKeepRealTime) {
  sim::SolverParams on;
  on.diffuse = 1.0f;
  sim::SolverParams p = on;
  EXPECT_TRUE(app::TurnOffDiffuseOutOfRealTime(0.95, false, &p));
  EXPECT_EQ(p.diffuse, 0.0f);
  p = on;
  EXPECT_FALSE(app::TurnOffDiffuseOutOfRealTime(1.0, false, &p)) << "real time kept: they stay";
  EXPECT_EQ(p.diffuse, 1.0f);
  EXPECT_FALSE(app::TurnOffDiffuseOutOfRealTime(0.5, true, &p)) << "the command line's own choice stays";
  EXPECT_EQ(p.diffuse, 1.0f);
  EXPECT_FALSE(app::TurnOffDiffuseOutOfRealTime(std::nan(""), false, &p)) << "no measurement: nothing changes";
  sim::SolverParams off;
  EXPECT_FALSE(app::TurnOffDiffuseOutOfRealTime(0.1, false, &off));
}

}  // namespace
}  // namespace sphxr::test
