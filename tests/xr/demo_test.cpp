// sphxr_xr_demo, the XR loop as a program, against the simulated headset: it exits cleanly, and the
// controller square it draws lands where a pinhole camera puts it in each eye (stereo parallax of
// the configured eye distance), a truth computed here in closed form from the runtime's field of view.
#include <cmath>

#include "xr_test_support.h"

namespace sphxr::xr::test {
namespace {

int RunDemo(const std::string& args, const std::filesystem::path& output) {
  std::string cmd = std::string(SPHXR_XR_DEMO) + " " + args + " >" + output.string() + " 2>&1";
  int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadText(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Centroid (x right, y down, in pixels) of the pixels that are clearly green.
bool GreenCentroid(const std::filesystem::path& png, double* cx, double* cy) {
  int w = 0, h = 0;
  std::vector<uint8_t> px;
  if (!ReadPng(png, &w, &h, &px)) return false;
  double sx = 0, sy = 0, n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = &px[(size_t(y) * w + x) * 4];
      if (p[1] > 200 && p[0] < 150) sx += x + 0.5, sy += y + 0.5, n += 1;
    }
  if (n == 0) return false;
  *cx = sx / n;
  *cy = sy / n;
  return true;
}

TEST(XrDemo, ControllerSquareShowsTheStereoParallax) {
  SimHeadset headset("demo");
  const int W = 400, H = 300;
  const double ipd = 0.064, distance = 1.0;
  headset.env.Set("SPHXR_SIM_XR_EYE_SIZE", "400x300");
  headset.env.Set("SPHXR_SIM_XR_IPD", "0.064");
  // Head at 1.5 m looking along -z; right controller 1 m straight ahead, trigger pressed.
  std::ofstream(headset.dir / "poses.txt") << "0 head 0 1.5 0 0 0 0 1\n"
                                              "0 right 0 1.5 -1 0 0 0 1 trigger=1\n"
                                              "0 left -0.3 0.5 0 0 0 0 1\n";
  headset.env.Set("SPHXR_SIM_XR_POSES", (headset.dir / "poses.txt").string());
  auto frames = headset.dir / "frames";
  std::filesystem::create_directories(frames);
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_DIR", frames.string());
  ASSERT_EQ(RunDemo("--frames 5", headset.dir / "out.txt"), 0) << ReadText(headset.dir / "out.txt");
  EXPECT_NE(ReadText(headset.dir / "out.txt").find("session ended after 5 frames"), std::string::npos)
      << ReadText(headset.dir / "out.txt");
  ExpectNoValidationErrors(headset);

  // The simulated headset's field of view (sim_runtime/src/spaces.cpp, kEyeFov): left eye
  // left/right/up/down = -0.80/0.75/0.80/-0.85 rad, the right eye mirrored left-right.
  auto column = [&](double x, double tanL, double tanR) { return (x / distance - tanL) / (tanR - tanL) * W; };
  const double tanUp = std::tan(0.80), tanDown = std::tan(-0.85);
  const double row = H - (0 - tanDown) / (tanUp - tanDown) * H;  // from the top
  const double leftColumn = column(+ipd / 2, std::tan(-0.80), std::tan(0.75));   // point is right of the left eye
  const double rightColumn = column(-ipd / 2, std::tan(-0.75), std::tan(0.80));  // and left of the right eye
  double lx, ly, rx, ry;
  ASSERT_TRUE(GreenCentroid(frames / "frame_000004_left.png", &lx, &ly));
  ASSERT_TRUE(GreenCentroid(frames / "frame_000004_right.png", &rx, &ry));
  // The square is drawn at the projected pixel (integer), so half a pixel either way plus rounding.
  EXPECT_NEAR(lx, leftColumn, 1.0);
  EXPECT_NEAR(rx, rightColumn, 1.0);
  EXPECT_NEAR(ly, row, 1.0);
  EXPECT_NEAR(ry, row, 1.0);
  EXPECT_GT(lx - rx, 20.0);  // the parallax itself: 33 px at 1 m for 6.4 cm between the eyes
}

TEST(XrDemo, NoRuntimeIsOneLineAndExitZero) {
  ScopedEnv env;
  env.Set("XR_RUNTIME_JSON", "/nonexistent/runtime.json");
  auto out = TempDir("demo_noruntime") / "out.txt";
  ASSERT_EQ(RunDemo("--frames 5", out), 0);
  std::string text = ReadText(out);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("no OpenXR runtime available"), std::string::npos) << text;
}

}  // namespace
}  // namespace sphxr::xr::test
