// A fixed scene (floor, tank, obstacle, paddle, a water mesh, particles) compared with a stored
// reference image, tests/data/render_reference.png. Tolerance: every channel within 6/255 and the mean
// absolute difference below 0.5/255, which allows llvmpipe's rounding to move between Mesa versions
// but not a changed shader, camera or pass. After an intended change of the look, regenerate with
//   SPHXR_UPDATE_REFERENCE=1 ./build-dev/tests/sphxr_render_tests --gtest_filter='ReferenceImage*'
// and look at the new image before committing it.
#include <cstdlib>
#include <filesystem>

#include "render_support.h"
#include "sphxr/app/pictures.h"

namespace sphxr::test {
namespace {

using ReferenceImageTest = RenderFixture;

TEST_F(ReferenceImageTest, FixedSceneMatchesTheStoredImage) {
  // Water mesh: a closed box of water in the tank's corner.
  const BoxMesh water(glm::vec3(0.02f, 0.0f, 0.02f), glm::vec3(0.25f, 0.12f, 0.2f));
  std::vector<sim::Vec4> particles, velocities;
  for (int i = 0; i < 50; ++i) {
    particles.push_back({0.3f + 0.005f * (i % 10), 0.02f + 0.01f * (i / 10), 0.1f, 0});
    velocities.push_back({0.05f * i, 0, 0, 0});
  }
  render::FrameScene scene;
  scene.tank = sim::Aabb{{0, 0, 0}, {0.4f, 0.3f, 0.25f}};
  scene.obstacles.push_back(sim::Aabb{{0.3f, 0, 0.15f}, {0.36f, 0.08f, 0.22f}});
  scene.solids.push_back(render::SolidMesh{{}, glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0.15f, 0.2f, 0.1f)),
                                                          glm::vec3(0.03f)), glm::vec3(0.95f, 0.55f, 0.15f)});
  scene.surface = water.View();
  scene.particles.position = particles.data();
  scene.particles.velocity = velocities.data();
  scene.particles.count = static_cast<int>(particles.size());
  scene.particles.radius = 0.004f;
  scene.absorptionScale = 4.0f;
  const render::Camera camera = render::FrameBox(scene.tank, float(kW) / kH);
  const render::View v = FullView(camera.View(), camera.Projection(float(kW) / kH));
  const render::Image img = DrawAndRead(scene, std::span(&v, 1));

  const std::string reference = SPHXR_TEST_DATA_DIR "/render_reference.png";
  if (std::getenv("SPHXR_UPDATE_REFERENCE")) {
    ASSERT_TRUE(app::WritePng(reference, img).ok());
    GTEST_SKIP() << "reference written to " << reference;
  }
  std::filesystem::create_directories(SPHXR_TEST_ARTIFACTS_DIR);
  ASSERT_TRUE(app::WritePng(std::string(SPHXR_TEST_ARTIFACTS_DIR) + "/reference_candidate.png", img).ok());
  render::Image expected;
  const Status read = app::ReadPng(reference, &expected);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_EQ(expected.width, img.width);
  ASSERT_EQ(expected.height, img.height);
  int worst = 0;
  double sum = 0.0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      for (int c = 0; c < 3; ++c) {
        const int d = std::abs(int(img.At(x, y)[c]) - int(expected.At(x, y)[c]));
        worst = std::max(worst, d);
        sum += d;
      }
    }
  }
  const double mean = sum / (3.0 * kW * kH);
  EXPECT_LE(worst, 6) << "largest channel difference (of 255); the candidate is in test-artifacts/";
  EXPECT_LT(mean, 0.5) << "mean absolute difference (of 255)";
}

}  // namespace
}  // namespace sphxr::test
