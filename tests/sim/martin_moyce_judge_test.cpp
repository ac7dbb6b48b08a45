// sim::JudgeMartinMoyce and sim::ReadMartinMoyce (sim/measure.h): the shared judge of the dam break
// against Martin & Moyce (1952). A simulation that is the experiment itself, released a known time
// earlier, must be judged with that lag and no deviation; a lag outside the judge's range shows at its
// end; a malformed measurements file is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sphxr/sim/measure.h"

namespace sphxr::sim {
namespace {

constexpr double kA = 0.05715, kG = 9.81;

// The measured series, piecewise linear in its own time, held at its ends.
double Curve(const std::vector<DamBreakPoint>& s, double t) {
  if (t <= s.front().t) return s.front().value;
  for (size_t i = 1; i < s.size(); ++i) {
    if (s[i].t >= t) return s[i - 1].value + (t - s[i - 1].t) / (s[i].t - s[i - 1].t) * (s[i].value - s[i - 1].value);
  }
  return s.back().value;
}

// A "simulation" that is the experiment released `lead` seconds earlier, sampled every 0.02 ms.
std::vector<DamBreakSample> Leading(const std::vector<DamBreakPoint>& front, const std::vector<DamBreakPoint>& height,
                                    double lead) {
  const double toT = std::sqrt(2.0 * kG / kA), toTau = std::sqrt(kG / kA);
  std::vector<DamBreakSample> s;
  for (double t = 0.0; t <= 0.235; t += 2e-5) {
    s.push_back({t, Curve(front, (t + lead) * toT), Curve(height, (t + lead) * toTau)});
  }
  return s;
}

void Read(std::vector<DamBreakPoint>* front, std::vector<DamBreakPoint>* height) {
  ASSERT_TRUE(ReadMartinMoyce(SPHXR_TEST_DATA_DIR "/martin_moyce_1952.csv", front, height));
  ASSERT_EQ(front->size(), 15u);
  ASSERT_EQ(height->size(), 17u);
}

TEST(MartinMoyceJudge, FindsTheLagOfTheExperimentItselfAndNoDeviation) {
  std::vector<DamBreakPoint> front, height;
  Read(&front, &height);
  if (HasFatalFailure()) return;
  const double lead = 0.006;
  DamBreakJudgement j;
  ASSERT_TRUE(JudgeMartinMoyce(Leading(front, height, lead), front, height, kA, kG, &j));
  EXPECT_NEAR(j.lagLimit, 0.41 / std::sqrt(2.0 * kG / kA), 1e-12);  // the first front time
  // The scan's step is at most 0.05 ms; the samples' own step 0.02 ms.
  EXPECT_NEAR(j.lag, lead, 5e-5);
  EXPECT_EQ(j.front.size(), 12u);  // 1 <= T <= 3.3
  EXPECT_EQ(j.height.size(), 12u);  // tau <= 3
  // Off by at most the slope times the scan's step: the front moves Z = 1.4 per unit T, 18.5 T per s.
  EXPECT_LT(j.frontMax, 1.4 * 18.5 * 5e-5 / 1.1);  // over the smallest compared Z, 1.44
  EXPECT_LT(j.heightMax, 0.01);
}

TEST(MartinMoyceJudge, ALagBeyondItsRangeShowsAtTheRangesEnd) {
  std::vector<DamBreakPoint> front, height;
  Read(&front, &height);
  if (HasFatalFailure()) return;
  DamBreakJudgement j;
  ASSERT_TRUE(JudgeMartinMoyce(Leading(front, height, 0.040), front, height, kA, kG, &j));
  EXPECT_DOUBLE_EQ(j.lag, j.lagLimit);
  EXPECT_GT(j.frontMax, 0.05);
  // A simulation slower than the experiment: the lag stays at 0.
  ASSERT_TRUE(JudgeMartinMoyce(Leading(front, height, -0.010), front, height, kA, kG, &j));
  EXPECT_EQ(j.lag, 0.0);
}

TEST(MartinMoyceJudge, AMalformedFileIsRefused) {
  const std::string path = ::testing::TempDir() + "/mm_malformed.csv";
  for (const char* text : {"series,t,v\nfront,0.4,1.1\nheight,0.5\n", "series,t,v\nfront,0.4,1.1\nwave,0.5,1\n",
                           "series,t,v\nfront,x,1.1\nheight,0.5,0.9\n", "series,t,v\nfront,0.4,1.1\n"}) {
    std::ofstream(path) << text;
    std::vector<DamBreakPoint> front, height;
    EXPECT_FALSE(ReadMartinMoyce(path, &front, &height)) << text;
  }
  std::vector<DamBreakPoint> front, height;
  EXPECT_FALSE(ReadMartinMoyce(path + ".absent", &front, &height));
  std::remove(path.c_str());
}

}  // namespace
}  // namespace sphxr::sim
