// Each shipped scene's headless picture (the real binary: `sphxr --headless --steps 2 --screenshot`,
// one thread, so the water is the same bits every run) against a committed reference image,
// tests/data/pictures/<scene>.png, by structural similarity (Wang, Bovik, Sheikh, Simoncelli, "Image
// quality assessment: from error visibility to structural similarity", IEEE TIP 13(4), 2004) of the
// luminance over 8x8 windows. The bound 0.99 lets llvmpipe's rounding move between Mesa versions (a
// few grey levels on a few pixels); a changed look fails it: the same scene without its shadows and foam
// (--render-quality low) and another scene's picture both score below it (checked here).
// After an intended change of the look: scripts/update_reference_pictures.sh, look at the images, and
// say in the commit why they changed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "sphxr/app/pictures.h"
#include "support.h"

namespace sphxr::test {
namespace {

constexpr double kBound = 0.99;
const char* const kScenes[] = {"buchner_2002", "dam_break", "dam_break_1m", "deep_tank", "stir", "tank_rest"};

std::vector<double> Luminance(const render::Image& img) {
  std::vector<double> y(static_cast<size_t>(img.width) * img.height);
  for (int j = 0; j < img.height; ++j) {
    for (int i = 0; i < img.width; ++i) {
      const uint8_t* p = img.At(i, j);
      y[static_cast<size_t>(j) * img.width + i] = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    }
  }
  return y;
}

/// Mean SSIM over 8x8 windows (stride 4) of the luminance, with the paper's constants (L = 255).
double Ssim(const render::Image& a, const render::Image& b) {
  if (a.width != b.width || a.height != b.height) return 0.0;
  const std::vector<double> x = Luminance(a), y = Luminance(b);
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double sum = 0.0;
  int windows = 0;
  for (int j = 0; j + 8 <= a.height; j += 4) {
    for (int i = 0; i + 8 <= a.width; i += 4) {
      double mx = 0, my = 0;
      for (int v = 0; v < 8; ++v) {
        for (int u = 0; u < 8; ++u) {
          mx += x[static_cast<size_t>(j + v) * a.width + i + u];
          my += y[static_cast<size_t>(j + v) * a.width + i + u];
        }
      }
      mx /= 64, my /= 64;
      double vx = 0, vy = 0, cov = 0;
      for (int v = 0; v < 8; ++v) {
        for (int u = 0; u < 8; ++u) {
          const double dx = x[static_cast<size_t>(j + v) * a.width + i + u] - mx;
          const double dy = y[static_cast<size_t>(j + v) * a.width + i + u] - my;
          vx += dx * dx, vy += dy * dy, cov += dx * dy;
        }
      }
      vx /= 63, vy /= 63, cov /= 63;
      sum += ((2 * mx * my + c1) * (2 * cov + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
      ++windows;
    }
  }
  return windows ? sum / windows : 0.0;
}

/// `length`: how long the run is ("--steps 2": the scene as it starts, its surface and paddles).
Status Picture(const std::string& scene, const std::string& png, const std::string& length = "--steps 2",
               const std::string& extra = "") {
  const std::string command = std::string("'") + SPHXR_BINARY + "' --headless --scene '" + SPHXR_SCENES_DIR + "/" + scene +
                              ".json' " + length + " --settle 0 --threads 1 --device cpu --image-size 320x180 --no-progress "
                              "--screenshot '" + png + "' " + extra + " >/dev/null 2>&1";
  const int status = std::system(command.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return Status::Error("sphxr failed for " + scene);
  return Status::Ok();
}

std::string Reference(const std::string& scene) { return std::string(SPHXR_TEST_DATA_DIR) + "/pictures/" + scene + ".png"; }

class ScenePictures : public ::testing::TestWithParam<const char*> {};

TEST_P(ScenePictures, MatchTheCommittedReference) {
  const std::string scene = GetParam();
  TempDir dir("scene_pictures");
  const std::string png = dir.File(scene + ".png");
  ASSERT_TRUE(Picture(scene, png).ok());
  render::Image shot;
  ASSERT_TRUE(app::ReadPng(png, &shot).ok());
  if (std::getenv("SPHXR_UPDATE_REFERENCE")) {
    std::filesystem::create_directories(std::filesystem::path(Reference(scene)).parent_path());
    std::filesystem::copy_file(png, Reference(scene), std::filesystem::copy_options::overwrite_existing);
    GTEST_SKIP() << "reference written to " << Reference(scene);
  }
  std::filesystem::create_directories(SPHXR_TEST_ARTIFACTS_DIR);
  std::filesystem::copy_file(png, std::string(SPHXR_TEST_ARTIFACTS_DIR) + "/scene_" + scene + ".png",
                             std::filesystem::copy_options::overwrite_existing);
  render::Image reference;
  const Status read = app::ReadPng(Reference(scene), &reference);
  ASSERT_TRUE(read.ok()) << read.message() << " (scripts/update_reference_pictures.sh writes it)";
  const double ssim = Ssim(shot, reference);
  std::printf("%s: SSIM %.5f against the reference\n", scene.c_str(), ssim);
  EXPECT_GE(ssim, kBound) << "the candidate is in test-artifacts/scene_" << scene << ".png";
}

INSTANTIATE_TEST_SUITE_P(Shipped, ScenePictures, ::testing::ValuesIn(kScenes),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

TEST(ScenePicturesBound, ALostEffectOrAnotherSceneFallsBelowIt) {
  TempDir dir("scene_pictures_bound");
  render::Image stir, stirLow, damBreak;
  ASSERT_TRUE(Picture("stir", dir.File("stir.png"), "--time 0.3").ok());
  ASSERT_TRUE(Picture("stir", dir.File("stir_low.png"), "--time 0.3", "--render-quality low").ok());
  ASSERT_TRUE(Picture("dam_break", dir.File("dam_break.png")).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("stir.png"), &stir).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("stir_low.png"), &stirLow).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("dam_break.png"), &damBreak).ok());
  const double self = Ssim(stir, stir), low = Ssim(stir, stirLow), other = Ssim(stir, damBreak);
  std::printf("SSIM: the same picture %.5f, without shadows and foam %.5f, another scene %.5f\n", self, low, other);
  EXPECT_DOUBLE_EQ(self, 1.0);
  EXPECT_LT(low, kBound);
  EXPECT_LT(other, kBound);
}

}  // namespace
}  // namespace sphxr::test
