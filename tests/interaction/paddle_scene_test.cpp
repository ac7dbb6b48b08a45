// The scene file's "paddles" section (app/src/scene_file.cpp) and the headless runner with paddles.
#include <gtest/gtest.h>

#include <cmath>

#include "sphxr/app/headless.h"
#include "sphxr/app/scene_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

const char* kTank = R"("tank": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.2, 0.1, 0.1] } ])";

Status Parse(const std::string& paddles, SceneFile* out) {
  return ParseScene(std::string("{") + kTank + ", \"paddles\": " + paddles + "}", "test.json", out);
}

void ExpectRefused(const std::string& paddles, const std::string& needle) {
  SceneFile scene;
  const Status s = Parse(paddles, &scene);
  ASSERT_FALSE(s.ok()) << paddles;
  EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
}

TEST(PaddleScene, StirSceneParses) {
  SceneFile scene;
  const Status s = LoadScene(SPHXR_SCENES_DIR "/stir.json", &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(scene.warnings.empty());
  ASSERT_EQ(scene.paddles.size(), 1u);
  const interaction::PaddleDesc& d = scene.paddles[0];
  EXPECT_EQ(d.holder, interaction::Holder::kScript);
  EXPECT_EQ(d.shapes.size(), 2u);
  EXPECT_EQ(d.trajectory.Keys().size(), 41u);
  EXPECT_TRUE(d.trajectory.Loop());
  EXPECT_EQ(scene.paddleFrameRate, 90.0);
  // A scene without the section has no paddles.
  SceneFile plain;
  ASSERT_TRUE(ParseScene(std::string("{") + kTank + "}", "plain.json", &plain).ok());
  EXPECT_TRUE(plain.paddles.empty());
}

TEST(PaddleScene, HandHeldDefaultsAndRefusals) {
  SceneFile scene;
  ASSERT_TRUE(Parse(R"({"list": [{"hand": "right", "shapes": "blade_on_handle", "limits": {"reentry_speed": 2}}]})", &scene).ok());
  ASSERT_EQ(scene.paddles.size(), 1u);
  EXPECT_EQ(scene.paddles[0].holder, interaction::Holder::kRightHand);
  EXPECT_EQ(scene.paddles[0].limits.reentrySpeed, 2.0f);
  EXPECT_EQ(scene.paddles[0].shapes.size(), 2u);

  ExpectRefused(R"([])", "paddles");
  ExpectRefused(R"({"list": [{"hand": "middle", "shapes": "blade_on_handle"}]})", "paddles.list[0].hand");
  ExpectRefused(R"({"list": [{"hand": "script", "shapes": "blade_on_handle"}]})", "trajectory");
  ExpectRefused(R"({"list": [{"hand": "script", "shapes": "blade_on_handle", "trajectory": "missing.csv"}]})", "missing.csv");
  ExpectRefused(R"({"list": [{"hand": "left", "shapes": [{"box": {"center": [0,0,0], "half_extents": [0.1,-1,0.1]}}]}]})",
                "half_extents");
  ExpectRefused(R"({"list": [{"hand": "left", "shapes": [{"capsule": {"a": [0,0,0], "b": [0,1,0]}}]}]})", "radius");
  ExpectRefused(R"({"list": [{"hand": "left", "shapes": "blade_on_handle", "limits": {"max_speed": 0}}]})",
                "max_speed");
  ExpectRefused(R"({"frame_rate": 0, "list": []})", "frame_rate");
}

TEST(PaddleScene, HeadlessStirRunsWithThePaddle) {
  Options options;
  options.scenePath = SPHXR_SCENES_DIR "/stir.json";
  options.device = sim::Device::kCpu;
  options.threads = 1;
  options.steps = 40;
  options.spacing = 0.02f;  // 15 x 8 x 15 lattice: quick
  options.progress = 0;
  RunSummary summary;
  const Status s = RunHeadless(options, &summary);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(summary.paddles, 1);
  EXPECT_GT(summary.paddleParticles, 10);
  EXPECT_EQ(summary.steps, 40);
  EXPECT_TRUE(std::isfinite(summary.maxSpeed));
  EXPECT_GT(summary.paddleMeanForce, 0.0) << "the paddle is in the water: buoyancy and drag";
  EXPECT_GE(summary.paddlePeakHaptic, 0.0f);
  EXPECT_LE(summary.paddlePeakHaptic, 1.0f);
  // The fluid lattice is not seeded inside the paddle: fewer particles than the full 15 x 8 x 15.
  EXPECT_LT(summary.fluid, 15 * 8 * 15);
}

}  // namespace
}  // namespace sphxr::app
