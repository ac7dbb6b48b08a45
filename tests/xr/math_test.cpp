// xr's math at the OpenXR boundary and the simulated headset's pose script: checked against
// hand-computed transforms (no display needed).
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "action_bindings.h"
#include "pose_script.h"
#include "sphxr/xr/math.h"

namespace sphxr::xr {
namespace {

constexpr float kPi = 3.14159265358979f;

void ExpectNear(Vec3 a, Vec3 b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

/// Clip-space (x, y, z, w) of a point under a matrix.
std::array<float, 4> Apply(const Mat4& m, Vec3 p) {
  std::array<float, 4> r{};
  for (int row = 0; row < 4; ++row) r[row] = m(row, 0) * p.x + m(row, 1) * p.y + m(row, 2) * p.z + m(row, 3);
  return r;
}

TEST(XrMath, RotationFollowsRightHandRule) {
  // 90 degrees about +y turns forward (-z) to the left (-x), and +x to -z.
  Quat q = AxisAngle({0, 1, 0}, kPi / 2);
  ExpectNear(Rotate(q, {0, 0, -1}), {-1, 0, 0});
  ExpectNear(Rotate(q, {1, 0, 0}), {0, 0, -1});
  // Composition: rotating by a then b equals rotating by Mul(b, a).
  Quat a = AxisAngle({1, 0, 0}, 0.3f), b = AxisAngle({0, 0, 1}, -1.1f);
  Vec3 v{0.2f, -0.7f, 1.3f};
  ExpectNear(Rotate(Mul(b, a), v), Rotate(b, Rotate(a, v)));
}

TEST(XrMath, PoseInverseAndComposition) {
  Pose p{{1, 2, 3}, Normalized({0.6f, 0.1f, 0.7f, -0.2f})};
  Pose id = p * Inverse(p);
  ExpectNear(id.position, {0, 0, 0});
  EXPECT_NEAR(std::fabs(id.orientation.w), 1.0f, 1e-5f);
  Vec3 v{0.5f, -1, 2};
  ExpectNear(Transform(Inverse(p), Transform(p, v)), v);
  // The matrix of a pose transforms points as the pose does.
  auto m = Apply(MatrixFromPose(p), v);
  ExpectNear({m[0], m[1], m[2]}, Transform(p, v));
}

TEST(XrMath, ViewMatrixPutsTheEyeAtTheOrigin) {
  Pose eye{{0.3f, 1.6f, -0.2f}, AxisAngle({0, 1, 0}, 0.4f)};
  auto o = Apply(ViewMatrix(eye), eye.position);
  ExpectNear({o[0], o[1], o[2]}, {0, 0, 0});
  // A point one metre ahead of the eye lands on the view axis at z = -1.
  auto f = Apply(ViewMatrix(eye), Transform(eye, {0, 0, -1}));
  ExpectNear({f[0], f[1], f[2]}, {0, 0, -1});
}

TEST(XrMath, ProjectionMapsTheFovEdgesToTheClipEdges) {
  Fov fov{-0.9f, 0.6f, 0.7f, -0.5f};  // asymmetric, as lenses are
  float n = 0.1f, far = 50.0f;
  Mat4 p = ProjectionMatrix(fov, n, far);
  auto ndc = [&](Vec3 v) {
    auto c = Apply(p, v);
    return Vec3{c[0] / c[3], c[1] / c[3], c[2] / c[3]};
  };
  float d = 2.0f;
  EXPECT_NEAR(ndc({d * std::tan(fov.angleLeft), 0, -d}).x, -1.0f, 1e-5f);
  EXPECT_NEAR(ndc({d * std::tan(fov.angleRight), 0, -d}).x, 1.0f, 1e-5f);
  EXPECT_NEAR(ndc({0, d * std::tan(fov.angleUp), -d}).y, 1.0f, 1e-5f);
  EXPECT_NEAR(ndc({0, d * std::tan(fov.angleDown), -d}).y, -1.0f, 1e-5f);
  EXPECT_NEAR(ndc({0, 0, -n}).z, -1.0f, 1e-5f);
  EXPECT_NEAR(ndc({0, 0, -far}).z, 1.0f, 1e-4f);
}

TEST(XrBindings, EveryProfileBindsGripTriggerAndHapticsOnBothHandsAndSaveOnAFreeButton) {
  std::set<std::string> profiles;
  for (const auto& b : SuggestedBindings()) profiles.insert(b.profile);
  EXPECT_EQ(profiles.size(), 5u);
  for (std::string p : {"/interaction_profiles/khr/simple_controller",
                         "/interaction_profiles/oculus/touch_controller",
                         "/interaction_profiles/valve/index_controller",
                         "/interaction_profiles/htc/vive_controller",
                         "/interaction_profiles/microsoft/motion_controller"})
    EXPECT_TRUE(profiles.count(p)) << p;
  for (const std::string& p : profiles) {
    for (ActionId a : {ActionId::kGripPose, ActionId::kTrigger, ActionId::kHaptic, ActionId::kRecentre, ActionId::kReset}) {
      uint8_t hands = 0;
      for (const auto& b : SuggestedBindings())
        if (b.profile == p && b.action == a) hands |= b.hands;
      uint8_t want = a == ActionId::kRecentre ? kLeftHand : a == ActionId::kReset ? kRightHand : kBothHands;
      EXPECT_EQ(hands, want) << p << " action " << int(a);
    }
    // Saving: the right B where the controller has one (Touch, Index), the trackpad click (Vive), the
    // thumbstick click (WMR), none on the simple controller (the mirror panel saves there), and never on
    // a path another action of the hand uses.
    std::string save;
    for (const auto& b : SuggestedBindings())
      if (b.profile == p && b.action == ActionId::kSaveState) {
        EXPECT_EQ(b.hands, kRightHand) << p;
        save = b.suffix;
      }
    const bool hasB = p.find("touch") != std::string::npos || p.find("index") != std::string::npos;
    const std::string want = hasB ? "/input/b/click"
                             : p.find("vive") != std::string::npos ? "/input/trackpad/click"
                             : p.find("microsoft") != std::string::npos ? "/input/thumbstick/click"
                                                                          : "";
    EXPECT_EQ(save, want) << p;
    for (const auto& b : SuggestedBindings()) {
      if (b.profile == p && b.action != ActionId::kSaveState && (b.hands & kRightHand)) {
        EXPECT_NE(std::string(b.suffix), save) << p;
      }
    }
  }
}

TEST(SimRuntimePoseScript, InterpolatesPositionsAndSlerpsOrientations) {
  simrt::PoseScript script;
  std::string error;
  // right hand: from x=0 to x=1 over 2 s while turning 0 -> 90 degrees about +y (quaternion of 90
  // degrees: (0, sin 45, 0, cos 45)).
  ASSERT_TRUE(simrt::PoseScript::Parse("# test\n"
                                       "0 right 0 1 0  0 0 0 1  trigger=0.25\n"
                                       "2 right 1 1 0  0 0.70710678 0 0.70710678 trigger=1 menu=1\n",
                                       &script, &error))
      << error;
  auto mid = script.Sample(simrt::Device::kRight, 1.0);
  ExpectNear(mid.pose.position, {0.5f, 1, 0});
  ExpectNear(Rotate(mid.pose.orientation, {0, 0, -1}), {-std::sin(kPi / 4), 0, -std::cos(kPi / 4)});
  EXPECT_FLOAT_EQ(mid.trigger, 0.25f);  // values hold the earlier key frame's value
  EXPECT_FALSE(mid.menu);
  auto end = script.Sample(simrt::Device::kRight, 5.0);
  ExpectNear(end.pose.position, {1, 1, 0});
  EXPECT_TRUE(end.menu);
  // A device without key frames keeps the default motion: the head of a person standing at the table
  // (eyes 1.55 m up) looks at the tank's centre (0, 1.0, -0.4) at arm's reach (under 0.8 m).
  auto head = script.Sample(simrt::Device::kHead, 0.0);
  EXPECT_NEAR(head.pose.position.y, 1.55f, 1e-6f);
  const Vec3 forward = Rotate(head.pose.orientation, {0, 0, -1});
  const Vec3 toTank{0.0f - head.pose.position.x, 1.0f - head.pose.position.y, -0.4f - head.pose.position.z};
  const float distance = std::sqrt(toTank.x * toTank.x + toTank.y * toTank.y + toTank.z * toTank.z);
  EXPECT_LT(distance, 0.8f);
  const float cosAngle = (forward.x * toTank.x + forward.y * toTank.y + forward.z * toTank.z) / distance;
  EXPECT_GT(cosAngle, std::cos(10.0f * kPi / 180.0f)) << "the head looks more than 10 degrees away from the tank";
}

TEST(SimRuntimePoseScript, BadLinesAreNamed) {
  simrt::PoseScript script;
  std::string error;
  EXPECT_FALSE(simrt::PoseScript::Parse("0 head 0 0 0 0 0 0 1\n1 elbow 0 0 0 0 0 0 1\n", &script, &error));
  EXPECT_NE(error.find("line 2"), std::string::npos) << error;
  EXPECT_NE(error.find("elbow"), std::string::npos) << error;
  EXPECT_FALSE(simrt::PoseScript::Parse("0 head 0 0 0 0 0 0 2\n", &script, &error));
  EXPECT_NE(error.find("unit quaternion"), std::string::npos) << error;
  EXPECT_FALSE(simrt::PoseScript::Parse("1 left 0 0 0 0 0 0 1\n0.5 left 0 0 0 0 0 0 1\n", &script, &error));
  EXPECT_NE(error.find("must not decrease"), std::string::npos) << error;
}

}  // namespace
}  // namespace sphxr::xr
