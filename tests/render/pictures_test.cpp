// Images of whole runs: `sphxr --headless --screenshot` (the real binary, EGL, no display) and the
// desktop window under a private Xvfb (opens, draws, the panel draws, scripted input moves the hand,
// keys act, closes cleanly). Images are kept under the build tree's test-artifacts/.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "render_support.h"
#include "sphxr/app/desktop.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "support.h"

namespace sphxr::test {
namespace {

// A small scene: a water block of 12 x 10 x 6 = 720 particles in a 0.2 x 0.15 x 0.1 m tank.
constexpr const char* kSmallScene = R"({
  "name": "small",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.15, 0.1] },
  "fluid": [ { "min": [0.04, 0.0, 0.02], "max": [0.16, 0.10, 0.08] } ],
  "run": { "steps": 2 }
})";

std::string ArtifactPath(const std::string& name) {
  std::filesystem::create_directories(SPHXR_TEST_ARTIFACTS_DIR);
  return (std::filesystem::path(SPHXR_TEST_ARTIFACTS_DIR) / name).string();
}

struct RunResult {
  int code = -1;
  std::string out, err;
};
RunResult RunBinary(const std::string& args, const TempDir& dir, const std::string& env = "") {
  const std::string out = dir.File("stdout.txt"), err = dir.File("stderr.txt");
  const std::string command = env + " '" SPHXR_BINARY "' " + args + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(command.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

bool Watery(glm::vec3 c) { return c.b > c.r + 0.08f && c.g > c.r; }

TEST(HeadlessPicturesTest, ScreenshotShowsWaterWhereTheFluidIsAndNowhereElse) {
  TempDir dir("pictures");
  const std::string scene = dir.Write("small.json", kSmallScene);
  const std::string png = dir.File("shot.png");
  const RunResult r = RunBinary("--headless --scene '" + scene + "' --no-progress --threads 1 --image-size 320x180 "
                                "--gl-debug --screenshot '" + png + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("picture         " + png), std::string::npos) << r.out;
  render::Image shot;
  const Status read = app::ReadPng(png, &shot);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_EQ(shot.width, 320);
  ASSERT_EQ(shot.height, 180);
  std::filesystem::copy_file(png, ArtifactPath("headless_small.png"), std::filesystem::copy_options::overwrite_existing);

  // The same scene without its water, drawn by the same renderer and camera: pixels that changed are
  // where water was drawn.
  app::SceneFile sf;
  ASSERT_TRUE(app::LoadScene(scene, &sf).ok());
  std::unique_ptr<app::OfflinePictures> pictures;
  const Status created = app::OfflinePictures::Create(320, 180, &pictures);
  ASSERT_TRUE(created.ok()) << created.message();
  sim::HostFluid none;
  const std::string emptyPng = dir.File("empty.png");
  ASSERT_TRUE(pictures->Write(app::MakeFrameScene(sf.setup, none, render::RenderMode::kWater), emptyPng).ok());
  render::Image empty;
  ASSERT_TRUE(app::ReadPng(emptyPng, &empty).ok());

  // Truth: the fluid block's projection through the camera that frames the tank (render::FrameBox).
  const render::Camera camera = render::FrameBox(sf.setup.tank, 320.0f / 180.0f);
  const glm::mat4 vp = camera.Projection(320.0f / 180.0f) * camera.View();
  render::View v;
  v.width = 320;
  v.height = 180;
  const sim::Aabb block = sf.setup.fluid[0].box;
  // Particle centres lie half a spacing inside the block, spheres reach 0.75 spacing around them.
  const float grow = 0.0025f;
  const glm::vec3 lo(block.min.x - grow, block.min.y - grow, block.min.z - grow);
  const glm::vec3 hi(block.max.x + grow, block.max.y + grow, block.max.z + grow);
  int inside = 0, insideWater = 0, outside = 0, outsideChanged = 0;
  for (int y = 3; y < 177; ++y) {
    for (int x = 3; x < 317; ++x) {
      int hits = 0;
      for (int dy = -3; dy <= 3; dy += 3) {
        for (int dx = -3; dx <= 3; dx += 3) {
          hits += RayHitsBox(camera.eye, RenderFixture::PixelRay(vp, camera.eye, x + dx + 0.5f, y + dy + 0.5f, v), lo, hi);
        }
      }
      const glm::vec3 c = RenderFixture::Rgb(shot, x, y), e = RenderFixture::Rgb(empty, x, y);
      const bool changed = glm::length(c - e) > 0.04f;
      if (hits == 9) {
        ++inside;
        insideWater += changed && Watery(c);
      } else if (hits == 0) {
        ++outside;
        outsideChanged += changed;
      }
    }
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GE(insideWater, inside * 95 / 100) << insideWater << " of " << inside;
  EXPECT_EQ(outsideChanged, 0) << "of " << outside << " pixels away from the water";
}

TEST(HeadlessPicturesTest, FramesWritesOnePngPerFrameInterval) {
  TempDir dir("frames");
  const std::string scene = dir.Write("small.json", kSmallScene);
  // 0.02 s at 100 fps with max_dt 1 ms: frames at t = 0, 0.01, 0.02 (the last step lands on 0.02 or just past it).
  const RunResult r = RunBinary("--headless --scene '" + scene + "' --time 0.02 --no-progress --threads 1 "
                                "--image-size 64x48 --fps 100 --frames '" + dir.File("frames") + "'", dir, "PATH=/usr/bin:/bin");
  ASSERT_EQ(r.code, 0) << r.err;
  int count = 0;
  for (int i = 0; i < 10; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", i);
    if (!std::filesystem::exists(std::filesystem::path(dir.File("frames")) / name)) break;
    ++count;
    render::Image img;
    ASSERT_TRUE(app::ReadPng((std::filesystem::path(dir.File("frames")) / name).string(), &img).ok());
    EXPECT_EQ(img.width, 64);
    EXPECT_EQ(img.height, 48);
  }
  EXPECT_EQ(count, 3) << r.out;
  EXPECT_NE(r.out.find("frames          3 PNG files"), std::string::npos) << r.out;
}

TEST(HeadlessPicturesTest, BadImageOptionsAreOneLineErrors) {
  TempDir dir("badimg");
  const std::string scene = dir.Write("small.json", kSmallScene);
  RunResult r = RunBinary("--headless --scene '" + scene + "' --image-size 12x", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--image-size 12x: must be WIDTHxHEIGHT"), std::string::npos) << r.err;
  r = RunBinary("--headless --scene '" + scene + "' --no-progress --screenshot /nonexistent/dir/x.png", dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("/nonexistent/dir/x.png: cannot write the PNG file"), std::string::npos) << r.err;
}

TEST(DesktopFallbackTest, NoDisplayMeansOneLineAndAHeadlessRun) {
  TempDir dir("nodisplay");
  const std::string scene = dir.Write("small.json", kSmallScene);
  const RunResult r = RunBinary("--desktop --scene '" + scene + "' --no-progress --threads 1", dir,
                                "env -u DISPLAY -u WAYLAND_DISPLAY");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("desktop window unavailable (no display (DISPLAY and WAYLAND_DISPLAY are not set)): running "
                       "headless"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("sphxr summary: small"), std::string::npos) << r.out;
}

/// A private X server for the test (Xvfb on a free display number), killed at the end.
class Xvfb {
 public:
  Xvfb() {
    for (int n = 90; n < 140; ++n) {
      if (std::filesystem::exists("/tmp/.X11-unix/X" + std::to_string(n)) ||
          std::filesystem::exists("/tmp/.X" + std::to_string(n) + "-lock")) {
        continue;
      }
      m_pid = fork();
      if (m_pid == 0) {
        const std::string display = ":" + std::to_string(n);
        execlp("Xvfb", "Xvfb", display.c_str(), "-screen", "0", "1024x768x24", "-nolisten", "tcp", (char*)nullptr);
        _exit(127);
      }
      for (int i = 0; i < 100; ++i) {
        if (std::filesystem::exists("/tmp/.X11-unix/X" + std::to_string(n))) {
          m_display = ":" + std::to_string(n);
          return;
        }
        int status;
        if (waitpid(m_pid, &status, WNOHANG) == m_pid) break;  // it exited: try the next number
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }
  ~Xvfb() {
    if (m_pid > 0) {
      kill(m_pid, SIGTERM);
      waitpid(m_pid, nullptr, 0);
    }
  }
  const std::string& Display() const { return m_display; }
  bool Alive() const { return m_pid > 0 && waitpid(m_pid, nullptr, WNOHANG) == 0; }

 private:
  pid_t m_pid = -1;
  std::string m_display;
};

bool Orange(glm::vec3 c) { return c.r > 0.6f && c.g > 0.25f && c.g < 0.7f && c.b < 0.35f; }

TEST(DesktopWindowTest, OpensDrawsRespondsToScriptedInputAndClosesCleanly) {
  Xvfb xvfb;
  ASSERT_FALSE(xvfb.Display().empty()) << "could not start Xvfb (install the xvfb package)";
  const char* previous = std::getenv("DISPLAY");
  const std::string saved = previous ? previous : "";
  setenv("DISPLAY", xvfb.Display().c_str(), 1);
  TempDir dir("desktop");
  app::Options options;
  options.scenePath = dir.Write("small.json", kSmallScene);
  options.windowWidth = 800;
  options.windowHeight = 500;
  options.threads = 1;
  options.vsync = false;
  options.glDebug = true;  // any GL error in the window (renderer or ImGui's backend) aborts the test
  {
    std::unique_ptr<app::DesktopApp> desktop;
    const Status s = app::DesktopApp::Create(options, &desktop);
    ASSERT_TRUE(s.ok()) << s.message();
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(desktop->Frame());
    EXPECT_GT(desktop->PanelVertexCount(), 100) << "the ImGui panel did not draw";
    EXPECT_FALSE(desktop->Hand().active);

    // A drag with the left button: press at one pixel right of the panel, move, and the hand follows the
    // cursor: its cube (orange) is drawn under the cursor, at the pixel the mouse points at.
    // The tank's centre projects to the window's centre (400, 250); the panel covers x < 370.
    // Both points lie above the water (a hand under water is tinted by it).
    const double x0 = 430, y0 = 192, x1 = 490, y1 = 186;
    desktop->OnCursor(x0, y0);
    desktop->OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, true);
    render::Image first, second;
    ASSERT_TRUE(desktop->Frame(&first));
    ASSERT_TRUE(desktop->Hand().active);
    const auto p0 = desktop->Hand().position;
    desktop->OnCursor(x1, y1);
    ASSERT_TRUE(desktop->Frame(&second));
    const auto p1 = desktop->Hand().position;
    EXPECT_GT(std::abs(p1[0] - p0[0]) + std::abs(p1[1] - p0[1]) + std::abs(p1[2] - p0[2]), 1e-3f) << "the hand did not move";
    EXPECT_TRUE(app::WritePng(ArtifactPath("desktop_drag_0.png"), first).ok());
    EXPECT_TRUE(app::WritePng(ArtifactPath("desktop_drag_1.png"), second).ok());
    ASSERT_EQ(first.width, 800);
    ASSERT_EQ(first.height, 500);
    const int h = first.height;
    EXPECT_TRUE(Orange(RenderFixture::Rgb(first, int(x0), h - 1 - int(y0)))) << "no hand under the cursor at the press";
    EXPECT_TRUE(Orange(RenderFixture::Rgb(second, int(x1), h - 1 - int(y1)))) << "no hand under the cursor after the move";
    EXPECT_FALSE(Orange(RenderFixture::Rgb(second, int(x0), h - 1 - int(y0)))) << "the hand stayed where it was";
    desktop->OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, false);
    ASSERT_TRUE(desktop->Frame());
    EXPECT_FALSE(desktop->Hand().active);

    // Keys: pause, render mode.
    EXPECT_FALSE(desktop->Paused());
    desktop->OnKey(GLFW_KEY_SPACE);
    EXPECT_TRUE(desktop->Paused());
    // Paused, the frame loop goes on drawing the same snapshot (it never waits on the simulation);
    // n steps once; r resets.
    // The worker finishes a step in flight and publishes it: wait until the count holds still.
    int64_t pausedAt = -1;
    for (int i = 0; i < 100 && desktop->SimSteps() != pausedAt; ++i) {
      pausedAt = desktop->SimSteps();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      ASSERT_TRUE(desktop->Frame());
    }
    const int framesBefore = desktop->FramesDrawn();
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(desktop->Frame());
    EXPECT_EQ(desktop->FramesDrawn(), framesBefore + 3);
    EXPECT_EQ(desktop->SimSteps(), pausedAt);
    desktop->OnKey(GLFW_KEY_N);
    for (int i = 0; i < 100 && desktop->SimSteps() == pausedAt; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      ASSERT_TRUE(desktop->Frame());
    }
    EXPECT_EQ(desktop->SimSteps(), pausedAt + 1) << "n steps exactly once";
    desktop->OnKey(GLFW_KEY_R);
    for (int i = 0; i < 100 && desktop->SimSteps() != 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      ASSERT_TRUE(desktop->Frame());
    }
    EXPECT_EQ(desktop->SimSteps(), 0) << "r rebuilds the scene";
    EXPECT_TRUE(desktop->Paused()) << "a reset keeps the pause";
    EXPECT_FALSE(desktop->ParticleMode());
    desktop->OnKey(GLFW_KEY_M);
    EXPECT_TRUE(desktop->ParticleMode());
    render::Image shot;
    ASSERT_TRUE(desktop->Frame(&shot));
    EXPECT_EQ(app::WritePng(ArtifactPath("desktop_window.png"), shot).ok(), true);
    EXPECT_GE(desktop->FramesDrawn(), 7);
  }  // closes the window, stops the simulation thread
  EXPECT_TRUE(xvfb.Alive()) << "the X server died";
  if (saved.empty()) {
    unsetenv("DISPLAY");
  } else {
    setenv("DISPLAY", saved.c_str(), 1);
  }
}

}  // namespace
}  // namespace sphxr::test
