// Images of whole runs: `sphxr --headless --screenshot` (the real binary, EGL, no display) and the
// desktop window under a private Xvfb (opens, draws, the panel draws, scripted input moves the hand,
// keys act, closes cleanly). Images are kept under the build tree's test-artifacts/.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <glm/gtc/quaternion.hpp>

#include "render_support.h"
#include "sphxr/app/desktop.h"
#include "sphxr/app/headless.h"
#include "sphxr/app/state_file.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/snapshot.h"
#include "interop_surface.h"  // app/src: InteropSurface
#include "sim_worker.h"        // app/src: SimWorker
#include "sphxr/render/interop.h"
#include "support.h"
#include "xvfb.h"

namespace sphxr::test {
namespace {

constexpr const char* kSmallScene = kSmallTankScene;  // tests/support.h: 720 particles

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
  // Water mode draws the surface mesh: the iso-surface phi = 0.5 lies on the block's faces (half a
  // spacing beyond the outer particle layer) and its edges and corners are rounded over about half a
  // spacing. Nothing may be drawn beyond the block grown by a quarter spacing; all within the block
  // shrunk by half a spacing must be water.
  const float grow = 0.0025f, shrink = 0.005f;
  const glm::vec3 lo(block.min.x - grow, block.min.y - grow, block.min.z - grow);
  const glm::vec3 hi(block.max.x + grow, block.max.y + grow, block.max.z + grow);
  const glm::vec3 loIn(block.min.x + shrink, block.min.y + shrink, block.min.z + shrink);
  const glm::vec3 hiIn(block.max.x - shrink, block.max.y - shrink, block.max.z - shrink);
  int inside = 0, insideWater = 0, outside = 0, outsideChanged = 0;
  for (int y = 3; y < 177; ++y) {
    for (int x = 3; x < 317; ++x) {
      int hits = 0, hitsIn = 0;
      for (int dy = -3; dy <= 3; dy += 3) {
        for (int dx = -3; dx <= 3; dx += 3) {
          const glm::vec3 ray = RenderFixture::PixelRay(vp, camera.eye, x + dx + 0.5f, y + dy + 0.5f, v);
          hits += RayHitsBox(camera.eye, ray, lo, hi);
          hitsIn += RayHitsBox(camera.eye, ray, loIn, hiIn);
        }
      }
      const glm::vec3 c = RenderFixture::Rgb(shot, x, y), e = RenderFixture::Rgb(empty, x, y);
      const bool changed = glm::length(c - e) > 0.04f;
      if (hitsIn == 9) {
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

// A PNG that cannot be written whole is an error (stbi_write_png ignored its write errors: a full disk
// left a truncated PNG and a success). /dev/full fails every write; it is not removed (not a regular
// file), and a partial regular file would be.
TEST(HeadlessPicturesTest, APngThatCannotBeWrittenWholeIsAnError) {
  render::Image image;
  image.width = 64;
  image.height = 48;
  image.rgba.assign(4 * 64 * 48, 200);
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Status s = app::WritePng("/dev/full", image);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("write failed"), std::string::npos) << s.message();
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/full")) << "a device is never removed";
  TempDir dir("png_ok");
  ASSERT_TRUE(app::WritePng(dir.File("a.png"), image).ok());
  render::Image back;
  ASSERT_TRUE(app::ReadPng(dir.File("a.png"), &back).ok());
  EXPECT_EQ(back.width, 64);
}

TEST(HeadlessPicturesTest, BadImageOptionsAreOneLineErrors) {
  TempDir dir("badimg");
  const std::string scene = dir.Write("small.json", kSmallScene);
  RunResult r = RunBinary("--headless --scene '" + scene + "' --image-size 12x", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--image-size 12x: must be WIDTHxHEIGHT"), std::string::npos) << r.err;
  r = RunBinary("--headless --scene '" + scene + "' --no-progress --screenshot /nonexistent/dir/x.png", dir);
  EXPECT_EQ(r.code, 1);
  // Refused before the run (the picture is written after it): the directory is checked first.
  EXPECT_NE(r.err.find("--screenshot /nonexistent/dir/x.png: cannot write into /nonexistent/dir"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("sphxr summary"), std::string::npos) << r.out;
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



glm::vec3 V(sim::Vec3 v) { return {v.x, v.y, v.z}; }
glm::vec3 V(const std::array<float, 3>& v) { return {v[0], v[1], v[2]}; }

/// The blade centre (the point the mouse places) of the snapshot's mouse paddle, world.
glm::vec3 BladeCentre(const app::PaddlePose& p) {
  const sim::Vec3 w = app::PaddleWorkingPoint(p.shapes);
  const interaction::Quat& q = p.pose.orientation;
  return V(p.pose.position) + glm::quat(q.w, q.x, q.y, q.z) * V(w);
}

/// Sets DISPLAY to a private Xvfb for the scope.
class DisplayScope {
 public:
  explicit DisplayScope(const std::string& display) {
    const char* previous = std::getenv("DISPLAY");
    m_saved = previous ? previous : "";
    setenv("DISPLAY", display.c_str(), 1);
  }
  ~DisplayScope() {
    if (m_saved.empty()) unsetenv("DISPLAY");
    else setenv("DISPLAY", m_saved.c_str(), 1);
  }

 private:
  std::string m_saved;
};

TEST(DesktopWindowTest, OpensDrawsRespondsToScriptedInputAndClosesCleanly) {
  Xvfb xvfb;
  ASSERT_FALSE(xvfb.Display().empty()) << "could not start Xvfb (install the xvfb package)";
  const DisplayScope display(xvfb.Display());
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
    // A scene without paddles gets a hand-held one for the mouse (the right hand), out of the water.
    ASSERT_EQ(desktop->Snapshot()->paddles.size(), 1u);
    EXPECT_EQ(desktop->Snapshot()->paddles[0].hand, 1);
    EXPECT_EQ(desktop->Hand().index, 1);
    EXPECT_GT(BladeCentre(desktop->Snapshot()->paddles[0]).y, 0.15f) << "a hand-held paddle starts above the tank";

    // A drag with the left button: press right of the panel, move, and the hand's target follows the
    // cursor (the paddle it holds follows in simulated time: DesktopPaddleTest below).
    // The tank's centre projects to the window's centre (400, 250); the panel covers x < 370.
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
}

// --load-state in the window: the water starts where a headless run saved it (every particle, and the
// clock), and a reset (r) returns there rather than to the scene's lattice; the s key saves the running
// state; a file from another scene is an error at start-up.
TEST(DesktopWindowTest, StartsFromAStateFileResetsToItAndSavesWithS) {
  Xvfb xvfb;
  ASSERT_FALSE(xvfb.Display().empty()) << "could not start Xvfb (install the xvfb package)";
  const DisplayScope display(xvfb.Display());
  TempDir dir("desktop_state");
  app::Options headless;
  headless.mode = app::Mode::kHeadless;
  headless.scenePath = dir.Write("small.json", kSmallScene);
  headless.steps = 40;
  headless.threads = 1;
  headless.progress = 0;
  headless.saveState = dir.File("small.state");
  app::RunSummary summary;
  ASSERT_TRUE(app::RunHeadless(headless, &summary).ok());
  app::StateFile state;
  ASSERT_TRUE(app::ReadStateFile(headless.saveState, &state).ok());
  ASSERT_GT(state.clock.time, 0.0);

  app::Options options;
  options.scenePath = headless.scenePath;
  options.loadState = headless.saveState;
  options.saveState = dir.File("window.state");  // where the s key saves
  options.windowWidth = 640;
  options.windowHeight = 400;
  options.threads = 1;
  options.vsync = false;
  {
    std::unique_ptr<app::DesktopApp> desktop;
    const Status s = app::DesktopApp::Create(options, &desktop);
    ASSERT_TRUE(s.ok()) << s.message();
    // First the water runs on from the file's time; then pause and reset: the rebuilt solver's first
    // snapshot (a new one, with no step) must be the file's state again, not the scene's lattice.
    std::shared_ptr<const app::SimSnapshot> before;
    for (int i = 0; i < 500; ++i) {
      ASSERT_TRUE(desktop->Frame());
      before = desktop->Snapshot();
      if (before && before->steps > 0 && before->last.time > state.clock.time) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_TRUE(before && before->steps > 0) << "the window's simulation did not run";
    EXPECT_GT(before->last.time, state.clock.time) << "it runs on from the file's time";
    desktop->OnKey(GLFW_KEY_SPACE);
    desktop->OnKey(GLFW_KEY_R);
    std::shared_ptr<const app::SimSnapshot> snap;
    for (int i = 0; i < 500; ++i) {
      ASSERT_TRUE(desktop->Frame());
      snap = desktop->Snapshot();
      if (snap && snap != before && snap->steps == 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_TRUE(snap && snap != before);
    ASSERT_EQ(snap->steps, 0) << "the reset did not arrive";
    EXPECT_EQ(snap->last.time, state.clock.time) << "the clock starts at the state's time";
    ASSERT_EQ(snap->fluid.size(), state.fluid.size());
    int differ = 0;
    for (size_t i = 0; i < state.fluid.size(); ++i) {
      const sim::Vec4 a = state.fluid.position[i], b = snap->fluid.position[i];
      if ((a.x != b.x || a.y != b.y || a.z != b.z || state.fluid.id[i] != snap->fluid.id[i]) && differ++ < 3) {
        ADD_FAILURE() << "particle " << i << " is not where the state file has it";
      }
    }
    EXPECT_EQ(differ, 0);

    // One step, then s: the window saves the running state, which a run can start from.
    desktop->OnKey(GLFW_KEY_N);
    for (int i = 0; i < 500 && !(desktop->Snapshot() && desktop->Snapshot()->steps == 1); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      ASSERT_TRUE(desktop->Frame());
    }
    const std::shared_ptr<const app::SimSnapshot> stepped = desktop->Snapshot();
    ASSERT_EQ(stepped->steps, 1);
    desktop->OnKey(GLFW_KEY_S);
    app::StateFile fromWindow;
    const Status read = app::ReadStateFile(options.saveState, &fromWindow);
    ASSERT_TRUE(read.ok()) << read.message();
    EXPECT_EQ(fromWindow.clock.time, stepped->last.time) << "the state of the paused window, one step on";
    EXPECT_GT(fromWindow.clock.time, state.clock.time);
    EXPECT_EQ(fromWindow.fluidCount, state.fluidCount);
    EXPECT_EQ(fromWindow.step, state.step + 1) << "the window's steps count on from the file's";
  }
  // A file from another scene is an error at start-up (not a silent start from the scene).
  app::Options other = headless;
  other.scenePath = dir.Write("other.json", R"({ "name": "other", "solver": { "spacing": 0.01, "max_dt": 0.001 },
    "tank": { "min": [0, 0, 0], "max": [0.2, 0.15, 0.1] },
    "fluid": [ { "min": [0.0, 0.0, 0.0], "max": [0.1, 0.1, 0.1] } ], "run": { "steps": 2 } })");
  other.saveState = dir.File("other.state");
  ASSERT_TRUE(app::RunHeadless(other, &summary).ok());
  options.loadState = other.saveState;
  std::unique_ptr<app::DesktopApp> refused;
  const Status s = app::DesktopApp::Create(options, &refused);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("another scene"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
  EXPECT_TRUE(xvfb.Alive()) << "the X server died";
}

}  // namespace
}  // namespace sphxr::test

namespace sphxr::test {
namespace {

// Water over the whole floor of a small tank, 6 cm deep: 20 x 6 x 12 = 1,440 particles at 1 cm, and a
// right-hand paddle (the mouse plays it): a blade 4 x 4.8 x 1.2 cm on a 6 cm handle, re-entering at
// 4 m/s so that the test spends its time on the stroke (the simulation runs at a few hundredths of real
// time on the shared machine).
constexpr const char* kPoolScene = R"({
  "name": "pool",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.1, 0.12] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.2, 0.06, 0.12] } ],
  "paddles": { "list": [ {
    "name": "mouse", "hand": "right",
    "shapes": [ { "box": { "center": [0, -0.084, 0], "half_extents": [0.02, 0.024, 0.006] } },
                { "capsule": { "a": [0, 0, 0], "b": [0, -0.06, 0], "radius": 0.006 } } ],
    "limits": { "reentry_speed": 4 },
    "haptics": { "full_scale_force": 4, "time_constant": 0.05 }
  } ] },
  "run": { "steps": 2 }
})";


TEST(DesktopPaddleTest, MouseDragMovesThePaddleThePaddleMovesTheWaterAndThePanelShowsItsHaptics) {
  Xvfb xvfb;
  ASSERT_FALSE(xvfb.Display().empty()) << "could not start Xvfb (install the xvfb package)";
  DisplayScope display(xvfb.Display());
  TempDir dir("desktop_paddle");
  app::Options options;
  options.scenePath = dir.Write("pool.json", kPoolScene);
  options.windowWidth = 800;
  options.windowHeight = 500;
  options.threads = 1;
  options.vsync = false;
  options.quality = 0;  // the scene's spacing
  options.glDebug = true;
  std::unique_ptr<app::DesktopApp> desktop;
  const Status s = app::DesktopApp::Create(options, &desktop);
  ASSERT_TRUE(s.ok()) << s.message();
  auto snapshot = [&] { return desktop->Snapshot(); };
  ASSERT_TRUE(desktop->Frame());
  ASSERT_EQ(snapshot()->paddles.size(), 1u) << "the mouse plays the scene's hand-held paddle (no default added)";
  EXPECT_EQ(snapshot()->paddles[0].hand, 1);
  EXPECT_EQ(desktop->Hand().index, 1);
  const float top = 0.1f;
  EXPECT_GT(BladeCentre(snapshot()->paddles[0]).y, top) << "a hand-held paddle starts out of the water";

  // Press right of the panel and find, with the button held, the cursor rows that put the blade's centre
  // 3 cm above the floor (under water) and the columns 6 cm apart along the drag, the simulation paused.
  desktop->OnKey(GLFW_KEY_SPACE);
  ASSERT_TRUE(desktop->Paused());
  const double x0 = 420;
  desktop->OnCursor(x0, 250);
  desktop->OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, true);
  double y = 250;
  while (y < 480 && desktop->Hand().position[1] > 0.03f) desktop->OnCursor(x0, y += 2);
  ASSERT_LT(desktop->Hand().position[1], 0.035f);
  const glm::vec3 target0 = V(desktop->Hand().position);
  double x1 = x0;
  while (x1 < 700 && glm::length(V(desktop->Hand().position) - target0) < 0.06f) desktop->OnCursor(x1 += 2, y);
  const glm::vec3 target1 = V(desktop->Hand().position);
  ASSERT_GT(glm::length(target1 - target0), 0.055f);
  desktop->OnCursor(x0, y);

  // The paddle enters the water at the press point (re-entry at 1 m/s of simulated time).
  const auto start = std::chrono::steady_clock::now();
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  // Each frame advances the simulation by the same 13 steps (N: one step while paused), about 3.3 ms of
  // simulated time. Free-running frames would make the stroke's speed in simulated time depend on how
  // fast the solver is (a faster solver, a slower stroke, and less water moved ahead of the blade);
  // stepped frames make the test the same on every machine.
  constexpr int kStepsPerFrame = 13;
  auto frame = [&] {
    if (!desktop->Frame()) return false;  // hands the newest cursor pose to the simulation
    const int64_t target = snapshot()->steps + kStepsPerFrame;
    for (int k = 0; k < kStepsPerFrame; ++k) desktop->OnKey(GLFW_KEY_N);
    while (snapshot()->steps < target && wall() < 120.0) {
      if (!desktop->Frame()) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
  };
  while (wall() < 60.0 && glm::length(BladeCentre(snapshot()->paddles[0]) - target0) > 0.005f) ASSERT_TRUE(frame());
  ASSERT_LT(glm::length(BladeCentre(snapshot()->paddles[0]) - target0), 0.005f)
      << "the paddle did not reach the mouse: t = " << snapshot()->last.time << " s after " << snapshot()->steps
      << " steps (" << snapshot()->stepsPerSecond << " steps/s, " << snapshot()->stepMs << " ms per step, surface "
      << snapshot()->surfaceMs << " ms), " << desktop->FramesDrawn() << " frames in " << wall() << " s";
  const double enterWall = wall();
  // Held still under water, it feels the water (buoyancy): the panel's haptic bar is not zero.
  float hapticInWater = 0.0f;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(frame());
    hapticInWater = std::max(hapticInWater, desktop->PanelHaptic());
  }
  EXPECT_GT(hapticInWater, 0.02f) << "the panel shows no haptic amplitude with the blade in the water";

  // The drag: the fluid's mean horizontal velocity along the drag, against the sideways one.
  const std::shared_ptr<const app::SimSnapshot> before = snapshot();
  const glm::vec3 along = glm::normalize(glm::vec3(target1.x - target0.x, 0, target1.z - target0.z));
  const glm::vec3 side = glm::cross(glm::vec3(0, 1, 0), along);
  auto meanVelocity = [](const app::SimSnapshot& snap, glm::vec3 dir) {
    double sum = 0;
    for (const sim::Vec4& v : snap.fluid.velocity) sum += v.x * dir.x + v.y * dir.y + v.z * dir.z;
    return snap.fluid.velocity.empty() ? 0.0 : sum / snap.fluid.velocity.size();
  };
  const double alongBefore = meanVelocity(*before, along), sideBefore = meanVelocity(*before, side);
  double alongPeak = 0.0, sidePeak = 0.0;
  float hapticPeak = 0.0f;
  auto measure = [&] {
    alongPeak = std::max(alongPeak, meanVelocity(*snapshot(), along));
    sidePeak = std::max(sidePeak, std::abs(meanVelocity(*snapshot(), side)));
    hapticPeak = std::max(hapticPeak, desktop->PanelHaptic());
  };
  for (int i = 1; i <= 20; ++i) {  // the cursor moves over 20 frames
    desktop->OnCursor(x0 + (x1 - x0) * i / 20.0, y);
    ASSERT_TRUE(frame());
    measure();
  }
  while (wall() < enterWall + 40.0 && glm::length(BladeCentre(snapshot()->paddles[0]) - target1) > 0.005f) {
    ASSERT_TRUE(frame());
    measure();
  }
  for (int i = 0; i < 5; ++i) {  // the water goes on for a few frames after the blade stops
    ASSERT_TRUE(frame());
    measure();
  }
  const std::shared_ptr<const app::SimSnapshot> after = snapshot();
  EXPECT_LT(glm::length(BladeCentre(after->paddles[0]) - target1), 0.005f) << "the paddle did not follow the drag";
  // Displacement of the water that was near the blade's path, along the drag (by particle id).
  std::vector<glm::vec3> startPos(before->fluid.size());
  for (size_t i = 0; i < before->fluid.size(); ++i) startPos[before->fluid.id[i]] = V(sim::Vec3{before->fluid.position[i].x, before->fluid.position[i].y, before->fluid.position[i].z});
  double nearShift = 0.0, farShift = 0.0;
  int near = 0, far = 0;
  for (size_t i = 0; i < after->fluid.size(); ++i) {
    const glm::vec3 p0 = startPos[after->fluid.id[i]];
    const glm::vec3 p1(after->fluid.position[i].x, after->fluid.position[i].y, after->fluid.position[i].z);
    // Ahead of the blade's start, within its reach: the water it swept.
    const float a = glm::dot(p0 - target0, along), b = std::abs(glm::dot(p0 - target0, side));
    if (a > 0.01f && a < 0.05f && b < 0.02f && std::abs(p0.y - target0.y) < 0.02f) {
      nearShift += glm::dot(p1 - p0, along);
      ++near;
    }
    if (b > 0.04f) {  // beside the path, towards the front and back walls
      farShift += glm::dot(p1 - p0, along);
      ++far;
    }
  }
  ASSERT_GT(near, 5);
  ASSERT_GT(far, 5);
  nearShift /= near;
  farShift /= far;
  std::printf("paddle drag: %.3f m; mean fluid velocity along the drag %.4f m/s (before %.4f), sideways %.4f (before %.4f);"
              " water ahead of the blade moved %.4f m along (%d particles), beside the path %.4f m (%d);"
              " haptic at rest %.2f, peak %.2f; force at the end %.3f N; %.2f ms per step, surface %.2f ms, %.3f simulated s"
              " in %.1f s\n",
              glm::length(target1 - target0), alongPeak, alongBefore, sidePeak, sideBefore, nearShift, near, farShift, far,
              hapticInWater, hapticPeak, Length(after->paddles[0].force), after->stepMs, after->surfaceMs,
              after->last.time, wall());
  // The plunge into the water left it sloshing: the stroke must add momentum along the drag to that.
  EXPECT_GT(alongPeak - alongBefore, 0.015) << "the water did not move along the drag";
  EXPECT_GT(nearShift, 0.004) << "the water ahead of the blade was not pushed";
  // Beside the path the water flows back round the blade (a return flow), so the water ahead of the blade
  // moved forward relative to it.
  EXPECT_GT(nearShift - farShift, 0.008) << "the water beside the path moved as much as the water ahead of the blade";
  EXPECT_GT(hapticPeak, hapticInWater) << "the stroke feels no stronger than the blade held still";
  desktop->OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, false);
  render::Image shot;
  ASSERT_TRUE(desktop->Frame(&shot));
  EXPECT_TRUE(app::WritePng(ArtifactPath("desktop_paddle.png"), shot).ok());
  EXPECT_GT(desktop->SurfaceTriangles(), 100) << "water mode draws the surface mesh";
  desktop.reset();
  EXPECT_TRUE(xvfb.Alive());
}

TEST(HeadlessPicturesTest, WaterScreenshotIsDrawnFromTheSurfaceMesh) {
  TempDir dir("surface_picture");
  const std::string scene = dir.Write("small.json", kSmallScene);
  const std::string png = dir.File("shot.png");
  const RunResult r = RunBinary("--headless --scene '" + scene + "' --no-progress --threads 1 --image-size 320x180 "
                                "--gl-debug --screenshot '" + png + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  render::Image shot;
  ASSERT_TRUE(app::ReadPng(png, &shot).ok());

  // The same run in this process (deterministic on the CPU), drawn three ways by the same renderer:
  // from the surface mesh, from the particles as water (no mesh), and without water.
  app::SceneFile sf;
  ASSERT_TRUE(app::LoadScene(scene, &sf).ok());
  sim::SolverConfig config;
  config.threads = 1;
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(sf.setup, config, &solver).ok());
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(solver->Step().ok());
  app::SimSnapshot snap;
  ASSERT_TRUE(app::CaptureSnapshot(*solver, nullptr, {}, &snap).ok());
  snap.setup = sf.setup;
  ASSERT_GT(snap.surface.TriangleCount(), 100);
  const render::FrameScene frame = app::MakeFrameScene(snap, render::RenderMode::kWater);
  EXPECT_EQ(frame.surface.vertexCount, snap.surface.VertexCount());
  std::unique_ptr<app::OfflinePictures> pictures;
  ASSERT_TRUE(app::OfflinePictures::Create(320, 180, &pictures).ok());
  render::Image mesh, sprites, empty;
  ASSERT_TRUE(pictures->Write(frame, dir.File("mesh.png")).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("mesh.png"), &mesh).ok());
  ASSERT_TRUE(pictures->Write(app::MakeFrameScene(sf.setup, snap.fluid, render::RenderMode::kWater), dir.File("sprites.png")).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("sprites.png"), &sprites).ok());
  sim::HostFluid none;
  ASSERT_TRUE(pictures->Write(app::MakeFrameScene(sf.setup, none, render::RenderMode::kWater), dir.File("empty.png")).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("empty.png"), &empty).ok());
  std::filesystem::copy_file(dir.File("mesh.png"), ArtifactPath("headless_surface.png"), std::filesystem::copy_options::overwrite_existing);
  std::filesystem::copy_file(dir.File("sprites.png"), ArtifactPath("headless_sprites.png"), std::filesystem::copy_options::overwrite_existing);

  auto isChanged = [&](int xx, int yy) {
    return glm::length(RenderFixture::Rgb(shot, xx, yy) - RenderFixture::Rgb(empty, xx, yy)) > 0.04f;
  };
  int differsFromMesh = 0, differsFromSprites = 0, water = 0, changed = 0;
  for (int yy = 0; yy < 180; ++yy) {
    for (int xx = 0; xx < 320; ++xx) {
      const glm::vec3 c = RenderFixture::Rgb(shot, xx, yy);
      differsFromMesh += glm::length(c - RenderFixture::Rgb(mesh, xx, yy)) > 2.5f / 255.0f;
      differsFromSprites += glm::length(c - RenderFixture::Rgb(sprites, xx, yy)) > 0.04f;
      // The water's body: changed pixels whose neighbours within 3 px all changed. At the rim the
      // water is a few millimetres thick and the refracted table behind it shows through.
      bool body = xx >= 3 && yy >= 3 && xx < 317 && yy < 177;
      for (int dy = -3; body && dy <= 3; ++dy) {
        for (int dx = -3; body && dx <= 3; ++dx) body = isChanged(xx + dx, yy + dy);
      }
      changed += body;
      water += body && Watery(c);
    }
  }
  std::printf("screenshot vs in-process mesh picture: %d pixels differ; vs particle water: %d; water pixels %d of %d changed\n",
              differsFromMesh, differsFromSprites, water, changed);
  EXPECT_EQ(differsFromMesh, 0) << "the binary's water is not the surface mesh";
  EXPECT_GT(differsFromSprites, 200) << "the mesh picture looks like the particle picture";
  EXPECT_GT(water, 2000);
  EXPECT_GE(water, changed * 95 / 100);
}

TEST(HeadlessPicturesTest, SnapshotWithTheSurfaceOnTheDeviceDrawsTheInteropMeshLikeTheHostMesh) {
  // The GPU path's frame (SurfacePath::kInterop): the snapshot has no host mesh, MakeFrameScene draws the
  // InteropMesh. No GPU here, so the solver (CPU backend) writes the mesh with WriteSurface into host memory
  // and Upload fills the GL buffers that CUDA would fill through Map/Unmap; the picture must be the host
  // path's, pixel for pixel.
  TempDir dir("interop_picture");
  app::SceneFile sf;
  ASSERT_TRUE(app::ParseScene(kSmallScene, "small", &sf).ok());
  sim::SolverConfig config;
  config.threads = 1;
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(sf.setup, config, &solver).ok());
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(solver->Step().ok());
  app::SimSnapshot host, device;
  ASSERT_TRUE(app::CaptureSnapshot(*solver, nullptr, {}, &host).ok());
  ASSERT_TRUE(app::CaptureSnapshot(*solver, nullptr, {}, &device, app::SurfacePath::kInterop).ok());
  host.setup = device.setup = sf.setup;
  ASSERT_TRUE(device.surfaceOnDevice);
  ASSERT_EQ(device.surfaceVertices, host.surface.VertexCount());
  ASSERT_GT(host.surface.TriangleCount(), 100);
  const int n = static_cast<int>(device.surfaceVertices);
  std::vector<float> positions(3 * n), normals(3 * n);
  ASSERT_TRUE(solver->WriteSurface({positions.data(), normals.data(), n}, nullptr).ok());
  EXPECT_EQ(positions, host.surface.positions);  // the two phases give the extraction's mesh, bit for bit
  EXPECT_EQ(normals, host.surface.normals);

  std::unique_ptr<app::OfflinePictures> pictures;
  ASSERT_TRUE(app::OfflinePictures::Create(320, 180, &pictures, true).ok());
  std::unique_ptr<render::InteropMesh> mesh;
  ASSERT_TRUE(render::InteropMesh::Create(n + 7, &mesh).ok());
  ASSERT_TRUE(mesh->Upload(positions.data(), normals.data(), n).ok());
  const render::FrameScene viaBuffers = app::MakeFrameScene(device, render::RenderMode::kWater,
                                                            render::ParticleColor::kSpeed, mesh.get());
  EXPECT_EQ(viaBuffers.deviceSurface, mesh.get());
  EXPECT_TRUE(viaBuffers.surface.Empty());
  const render::FrameScene viaHost = app::MakeFrameScene(host, render::RenderMode::kWater,
                                                         render::ParticleColor::kSpeed, mesh.get());
  EXPECT_EQ(viaHost.deviceSurface, nullptr) << "a host snapshot draws its own mesh";
  EXPECT_EQ(app::MakeFrameScene(device, render::RenderMode::kParticles).deviceSurface, nullptr);
  render::Image a, b;
  ASSERT_TRUE(pictures->Write(viaHost, dir.File("host.png")).ok());
  ASSERT_TRUE(pictures->Write(viaBuffers, dir.File("buffers.png")).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("host.png"), &a).ok());
  ASSERT_TRUE(app::ReadPng(dir.File("buffers.png"), &b).ok());
  ASSERT_EQ(a.rgba.size(), b.rgba.size());
  int differing = 0, water = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) differing += a.rgba[i] != b.rgba[i];
  for (int yy = 0; yy < 180; ++yy) {
    for (int xx = 0; xx < 320; ++xx) water += Watery(RenderFixture::Rgb(a, xx, yy));
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(water, 2000);
  mesh.reset();  // its GL buffers go while the context is current
}

TEST(HeadlessPicturesTest, InteropFailureFallsBackToHostCopiesOnce) {
  // The GL thread's half of the interop path on a machine without a GPU: the worker (forced onto the
  // interop path, its solver on the CPU) builds without copying; the first write creates the buffers and
  // fails at Map, as it would where the GL context is not on the CUDA device; the worker then goes back
  // to host copies, with one warning.
  app::SceneFile sf;
  ASSERT_TRUE(app::ParseScene(kSmallScene, "small", &sf).ok());
  std::unique_ptr<app::OfflinePictures> pictures;  // a current GL context for the interop buffers
  ASSERT_TRUE(app::OfflinePictures::Create(64, 64, &pictures, true).ok());
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
  config.threads = 1;
  LogCapture log;
  app::SimWorker worker(config);
  ASSERT_TRUE(worker.Start(app::SimSceneFromFile(sf)).ok());
  worker.SetPaused(true);
  worker.ForceSurfacePathForTests(app::SurfacePath::kInterop);
  auto waitFor = [&](auto predicate) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    std::shared_ptr<const app::SimSnapshot> s = worker.Latest();
    while (!predicate(*s) && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      s = worker.Latest();
    }
    return s;
  };
  const auto onDevice = waitFor([](const app::SimSnapshot& s) { return s.surfaceOnDevice; });
  ASSERT_TRUE(onDevice->surfaceOnDevice);
  EXPECT_GT(onDevice->surfaceBuild, 0u);
  EXPECT_GT(onDevice->surfaceVertices, 300);
  EXPECT_EQ(onDevice->surface.VertexCount(), 0);
  app::InteropSurface interop;
  EXPECT_EQ(interop.Update(worker, *onDevice), nullptr);
  EXPECT_EQ(worker.Path(), app::SurfacePath::kHostCopy);
  EXPECT_EQ(interop.Update(worker, *onDevice), nullptr);  // again: host path now, no second warning
  const auto host = waitFor([](const app::SimSnapshot& s) { return !s.surfaceOnDevice && s.surface.VertexCount() > 0; });
  EXPECT_FALSE(host->surfaceOnDevice);
  EXPECT_EQ(host->surface.VertexCount(), onDevice->surfaceVertices) << "paused: the same state, the same mesh";
  worker.Stop();
  EXPECT_EQ(log.Count("CUDA-GL interop failed", LogLevel::kWarn), 1) << log.All();
  EXPECT_EQ(log.Count("interop buffers grown"), 1) << log.All();
  interop.Reset();  // its GL buffers go while the context is current
}

}  // namespace
}  // namespace sphxr::test

namespace sphxr::test {
namespace {

// The paddle's solids land where its primitives are: the unit cube's corners on the box's corners, the
// cylinder's axis on the capsule's segment, the spheres at its ends, for a rotated and moved body.
TEST(PaddleSolidsTest, BoxAndCapsuleAreDrawnAtTheBodyPose) {
  app::PaddlePose paddle;
  sim::ShapePrimitive box;
  box.kind = sim::ShapePrimitive::Kind::kBox;
  box.a = {0.0f, -0.1f, 0.0f};
  box.b = {0.03f, 0.04f, 0.005f};
  sim::ShapePrimitive capsule;
  capsule.kind = sim::ShapePrimitive::Kind::kCapsule;
  capsule.a = {0.0f, 0.0f, 0.0f};
  capsule.b = {0.0f, -0.06f, 0.02f};
  capsule.radius = 0.01f;
  paddle.shapes = {box, capsule};
  const glm::quat q = glm::angleAxis(0.7f, glm::normalize(glm::vec3(0.3f, 1.0f, -0.2f)));
  paddle.pose.position = {0.1f, 0.2f, 0.05f};
  paddle.pose.orientation = {q.w, q.x, q.y, q.z};
  paddle.hand = 1;
  std::vector<render::SolidMesh> solids;
  app::AppendPaddleSolids(paddle, &solids);
  ASSERT_EQ(solids.size(), 4u);  // box, cylinder, two spheres
  auto world = [&](glm::vec3 body) { return glm::vec3(0.1f, 0.2f, 0.05f) + q * body; };
  auto near = [](glm::vec3 a, glm::vec3 b) { return glm::length(a - b) < 1e-5f; };
  // Box: the unit cube centred at the origin (empty mesh).
  EXPECT_TRUE(solids[0].mesh.Empty());
  for (int c = 0; c < 8; ++c) {
    const glm::vec3 s((c & 1) ? 0.5f : -0.5f, (c & 2) ? 0.5f : -0.5f, (c & 4) ? 0.5f : -0.5f);
    const glm::vec3 expect = world(V(box.a) + 2.0f * s * V(box.b));
    EXPECT_TRUE(near(glm::vec3(solids[0].model * glm::vec4(s, 1.0f)), expect)) << "corner " << c;
  }
  // Cylinder: radius 1 along y from 0 to 1 -> from a to b with the capsule's radius.
  EXPECT_FALSE(solids[1].mesh.Empty());
  EXPECT_TRUE(near(glm::vec3(solids[1].model * glm::vec4(0, 0, 0, 1)), world(V(capsule.a))));
  EXPECT_TRUE(near(glm::vec3(solids[1].model * glm::vec4(0, 1, 0, 1)), world(V(capsule.b))));
  const glm::vec3 rim = glm::vec3(solids[1].model * glm::vec4(1, 0, 0, 1)) - world(V(capsule.a));
  EXPECT_NEAR(glm::length(rim), capsule.radius, 1e-6f);
  EXPECT_NEAR(glm::dot(rim, q * glm::normalize(V(capsule.b) - V(capsule.a))), 0.0f, 1e-6f);
  // The cylinder's vertices lie on the capsule's surface (distance to the segment = radius); the spheres'
  // within it (their inner halves are hidden in the cylinder).
  for (size_t k = 1; k < solids.size(); ++k) {
    const render::MeshView& m = solids[k].mesh;
    for (int v = 0; v < m.vertexCount; ++v) {
      const glm::vec3 p(solids[k].model * glm::vec4(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2], 1));
      const glm::vec3 a = world(V(capsule.a)), b = world(V(capsule.b));
      const float t = std::clamp(glm::dot(p - a, b - a) / glm::dot(b - a, b - a), 0.0f, 1.0f);
      const float d = glm::length(p - (a + t * (b - a)));
      if (k == 1) ASSERT_NEAR(d, capsule.radius, 1e-5f) << "cylinder vertex " << v;
      else ASSERT_LT(d, capsule.radius + 1e-5f) << "sphere " << k << " vertex " << v;
    }
  }
}

}  // namespace
}  // namespace sphxr::test
