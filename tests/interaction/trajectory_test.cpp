// Scripted trajectories (interaction/src/trajectory.cpp): the CSV format, interpolation against closed
// forms, tracking gaps, looping, and one-line refusals of bad files.
#include <gtest/gtest.h>

#include <cmath>

#include "sphxr/interaction/trajectory.h"
#include "refusal.h"
#include "support.h"

namespace sphxr::interaction {
namespace {

Trajectory ParseOk(const std::string& text) {
  Trajectory t;
  const Status s = Trajectory::Parse(text, "t.csv", &t);
  EXPECT_TRUE(s.ok()) << s.message();
  return t;
}

void ExpectRefused(const std::string& text, const std::string& needle) {
  Trajectory t;
  const Status s = Trajectory::Parse(text, "t.csv", &t);
  ASSERT_FALSE(s.ok()) << text;
  EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("t.csv"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
}

TEST(Trajectory, InterpolatesPositionLinearlyAndRotationBySlerp) {
  // 0 -> 90 degrees about y over one second; quaternions (cos a/2, 0, sin a/2, 0).
  const float s45 = std::sqrt(0.5f);
  const Trajectory t = ParseOk(Format("# comment\ntime,px,py,pz,qw,qx,qy,qz\n0, 0, 1, 0, 1, 0, 0, 0\n\n"
                                      "1, 2, 1, -4, %.8f, 0, %.8f, 0\n",
                                      s45, s45));
  ASSERT_EQ(t.Keys().size(), 2u);
  const HandInput h = t.Sample(0.25);
  EXPECT_TRUE(h.tracked);
  EXPECT_FALSE(h.hasVelocity);
  EXPECT_NEAR(h.pose.position.x, 0.5f, 1e-6f);
  EXPECT_NEAR(h.pose.position.y, 1.0f, 1e-6f);
  EXPECT_NEAR(h.pose.position.z, -1.0f, 1e-6f);
  // a quarter of 90 degrees = 22.5 degrees: slerp is uniform in angle (nlerp would not be)
  const float half = 0.5f * 22.5f * 3.14159265f / 180.0f;
  EXPECT_NEAR(h.pose.orientation.w, std::cos(half), 1e-5f);
  EXPECT_NEAR(h.pose.orientation.y, std::sin(half), 1e-5f);
  // before the first key and after the last: held
  EXPECT_EQ(t.Sample(-3.0).pose.position.x, 0.0f);
  EXPECT_EQ(t.Sample(7.0).pose.position.x, 2.0f);
}

TEST(Trajectory, UntrackedKeysMakeAGapAndLoopingRepeats) {
  Trajectory t = ParseOk("0,0,0,0,1,0,0,0,1\n1,1,0,0,1,0,0,0,1\n2,2,0,0,1,0,0,0,0\n3,3,0,0,1,0,0,0,1,0.5,1\n");
  EXPECT_TRUE(t.Sample(0.5).tracked);
  EXPECT_FALSE(t.Sample(1.5).tracked);  // next key untracked
  EXPECT_FALSE(t.Sample(2.5).tracked);  // this key untracked
  EXPECT_TRUE(t.Sample(3.0).tracked);
  EXPECT_FLOAT_EQ(t.Sample(3.0).trigger, 0.5f);
  t.SetLoop(true);  // period 3 s
  EXPECT_NEAR(t.Sample(3.5).pose.position.x, 0.5f, 1e-5f);
  EXPECT_NEAR(t.Sample(7.25).pose.position.x, 1.25f, 1e-5f);
  // Four columns: identity orientation.
  const Trajectory p = ParseOk("0, 1, 2, 3\n");
  EXPECT_EQ(p.Sample(0).pose.orientation.w, 1.0f);
}

TEST(Trajectory, BadFilesAreRefusedWithTheLine) {
  ExpectRefused("0,0,0,0\n0,1,0,0\n", "t.csv:2");
  ExpectRefused("0,0,0\n", "columns");
  ExpectRefused("0,0,x,0\n", "column 3");
  ExpectRefused("0,0,0,0,0,0,0,0\n", "quaternion");
  ExpectRefused("0,0,0,0,1,0,0,0,2\n", "tracked");
  ExpectRefused("# nothing\n", "no keys");
  Trajectory t;
  const Status s = Trajectory::Load("/nonexistent/path.csv", &t);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("/nonexistent/path.csv"), std::string::npos);
}

TEST(Trajectory, ValuesBeyondAFloatNameTheFileAndLine) {
  for (const char* value : {"1e300", "3e38", "-3e38"}) {
    interaction::Trajectory t;
    const std::string text = std::string("time,px,py,pz\n0,0.1,0.1,0.1\n1,") + value + ",0.1,0.1\n";
    test::ExpectBriefRefusal(interaction::Trajectory::Parse(text, "hand.csv", &t), "hand.csv:3: column 2");
  }
  interaction::Trajectory t;
  test::ExpectBriefRefusal(interaction::Trajectory::Parse("0,0,0,0\n1e12,0,0,0\n", "hand.csv", &t), "hand.csv:2: column 1");
  test::ExpectBriefRefusal(interaction::Trajectory::Parse("0,0,0,0\n1,0,0," + std::string(10000, '9') + "x\n", "hand.csv", &t),
                     "is not a finite number");
}

}  // namespace
}  // namespace sphxr::interaction
