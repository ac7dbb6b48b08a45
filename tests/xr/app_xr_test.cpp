// `sphxr --xr`, the real program, through the real Khronos loader with the core validation layer,
// against the simulated headset (scripted head and controller, eye images saved as PNG, haptic
// requests logged): the session runs to a clean exit, both eyes show the water where the fluid is
// (with the parallax of the eye distance), a missing runtime or a failing one falls back with one line
// and exit 0, a session lost mid-run ends cleanly.
#include <cmath>

#include "xr_test_support.h"

namespace sphxr::xr::test {
namespace {

struct AppRun {
  int code = -1;
  std::string out;  // stdout and stderr
};

AppRun RunSphxr(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path output = dir / "sphxr_out.txt";
  // In the test's own directory: files the program names itself (a lost session's state) land there.
  const std::string cmd = "cd '" + std::filesystem::absolute(dir).string() + "' && " + std::string(SPHXR_BINARY) + " " +
                          args + " >" + output.string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  AppRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(output);
  r.out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return r;
}

int CountOf(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

/// A small tank (0.2 m cube, water 0.1 m deep, 4,000 particles at 1 cm): the app places its centre at
/// (0, 1.0, -0.4) in the play space (app/include/sphxr/app/xr_mode.h).
/// `walls`: the tank's wall_pressure model ("mirrored", the default, or "wall_density").
std::filesystem::path WriteScene(const std::filesystem::path& dir, const std::string& paddles = "",
                                 const std::string& walls = "mirrored") {
  const std::filesystem::path path = dir / "scene.json";
  std::ofstream(path) << R"({
  "name": "xr_test_tank",
  "solver": { "spacing": 0.01, "stiffness": 57000.0, "viscosity": 0.3, "boundary_viscosity": 0.3, "max_dt": 0.001 },
  "tank": { "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2], "wall_pressure": ")" << walls << R"(" },
  "fluid": [ { "min": [0.0, 0.0, 0.0], "max": [0.2, 0.1, 0.2], "hydrostatic": true } ])"
                      << paddles << R"(
})";
  return path;
}

constexpr int kEyeW = 200, kEyeH = 160;
constexpr double kIpd = 0.064;
// The head 0.2 m in front of the tank and 0.3 m above its centre, looking 30 degrees down.
constexpr double kHeadX = 0.0, kHeadY = 1.3, kHeadZ = 0.2, kPitch = -30.0 * M_PI / 180.0;
// The water in the play space: the scene's fluid block shifted by the app's placement.
constexpr double kWaterMin[3] = {-0.1, 0.9, -0.5}, kWaterMax[3] = {0.1, 1.0, -0.3};

void SetUpHeadset(SimHeadset& h, const std::string& rightController = "") {
  h.env.Set("SPHXR_SIM_XR_EYE_SIZE", std::to_string(kEyeW) + "x" + std::to_string(kEyeH));
  h.env.Set("SPHXR_SIM_XR_IPD", "0.064");
  std::ofstream poses(h.dir / "poses.txt");
  poses << "0 head " << kHeadX << " " << kHeadY << " " << kHeadZ << " " << std::sin(kPitch / 2) << " 0 0 "
        << std::cos(kPitch / 2) << "\n";
  poses << "0 left -0.3 0.8 0.1 0 0 0 1\n";  // the left hand at the side, away from the water
  poses << (rightController.empty() ? "0 right 0.3 0.8 0.1 0 0 0 1\n" : rightController);
  poses.close();
  h.env.Set("SPHXR_SIM_XR_POSES", (h.dir / "poses.txt").string());
}

/// Pixel (x right, y down from the top) of a play-space point in one eye of the scripted head.
bool Project(int eye, const double p[3], double* px, double* py) {
  // Eye position: the head's, shifted by -/+ ipd/2 along the head's x axis (which the pitch keeps).
  const double ex = kHeadX + (eye == 0 ? -0.5 : 0.5) * kIpd;
  const double d[3] = {p[0] - ex, p[1] - kHeadY, p[2] - kHeadZ};
  // Into the eye frame: rotate by -pitch about x.
  const double c = std::cos(-kPitch), s = std::sin(-kPitch);
  const double x = d[0], y = c * d[1] - s * d[2], z = s * d[1] + c * d[2];
  if (z >= 0) return false;
  const double tx = x / -z, ty = y / -z;
  // sim_runtime's field of view: left eye -0.80/0.75/0.80/-0.85 rad, the right eye mirrored left-right.
  const double l = std::tan(eye == 0 ? -0.80 : -0.75), r = std::tan(eye == 0 ? 0.75 : 0.80);
  const double u = std::tan(0.80), dn = std::tan(-0.85);
  *px = (tx - l) / (r - l) * kEyeW;
  *py = kEyeH - (ty - dn) / (u - dn) * kEyeH;
  return true;
}

struct Box2 {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
};
Box2 ProjectedWater(int eye) {
  Box2 b;
  for (int i = 0; i < 8; ++i) {
    const double p[3] = {(i & 1) ? kWaterMax[0] : kWaterMin[0], (i & 2) ? kWaterMax[1] : kWaterMin[1],
                         (i & 4) ? kWaterMax[2] : kWaterMin[2]};
    double x = 0, y = 0;
    EXPECT_TRUE(Project(eye, p, &x, &y));
    b.x0 = std::min(b.x0, x), b.x1 = std::max(b.x1, x), b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
  }
  return b;
}

/// Water as the renderer shades it: blue-green with little red (measured: (42,116,143) to (78,122,145));
/// the sky has more red (138,174,231 at its deepest), the floor is grey-blue, the tank's edges dark.
bool IsWater(const uint8_t* p) { return p[0] < 100 && p[1] > p[0] + 25 && p[2] > p[0] + 40; }

/// The last captured pair of eye images.
std::pair<std::filesystem::path, std::filesystem::path> LastPair(const std::filesystem::path& dir) {
  std::vector<std::string> lefts;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.find("_left.png") != std::string::npos) lefts.push_back(name);
  }
  std::sort(lefts.begin(), lefts.end());
  if (lefts.empty()) return {};
  std::string right = lefts.back();
  right.replace(right.find("_left"), 5, "_right");
  return {dir / lefts.back(), dir / right};
}

struct WaterPixels {
  int count = 0, inside = 0;
  double cx = 0, cy = 0;
};
WaterPixels FindWater(const std::filesystem::path& png, const Box2& box) {
  WaterPixels w;
  int width = 0, height = 0;
  std::vector<uint8_t> px;
  EXPECT_TRUE(ReadPng(png, &width, &height, &px)) << png;
  EXPECT_EQ(width, kEyeW);
  EXPECT_EQ(height, kEyeH);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (!IsWater(&px[(size_t(y) * width + x) * 4])) continue;
      ++w.count;
      w.cx += x + 0.5, w.cy += y + 0.5;
      if (x + 0.5 >= box.x0 - 3 && x + 0.5 <= box.x1 + 3 && y + 0.5 >= box.y0 - 3 && y + 0.5 <= box.y1 + 3) ++w.inside;
    }
  if (w.count > 0) w.cx /= w.count, w.cy /= w.count;
  return w;
}

const std::string kCommon = " --quality scene --threads 1 --window-size 160x120";

TEST(XrApp, WaterInBothEyesWithParallaxAndACleanExit) {
  SimHeadset headset("app_water");
  SetUpHeadset(headset);
  const auto frames = headset.dir / "frames";
  std::filesystem::create_directories(frames);
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_DIR", frames.string());
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_EVERY", "10");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 30" + kCommon,
                         headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("sphxr --xr: OpenXR session ended after 30 frames"), std::string::npos) << r.out;
  // The specification's life cycle, as the simulated headset drives it, to the end.
  EXPECT_NE(r.out.find("sphxr --xr: session states IDLE READY SYNCHRONIZED VISIBLE FOCUSED VISIBLE SYNCHRONIZED "
                       "STOPPING IDLE EXITING\n"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(CountOf(r.out, "error"), 0) << r.out;
  ExpectNoValidationErrors(headset);

  const auto [left, right] = LastPair(frames);
  ASSERT_TRUE(std::filesystem::exists(left)) << r.out;
  ASSERT_TRUE(std::filesystem::exists(right));
  const Box2 boxL = ProjectedWater(0), boxR = ProjectedWater(1);
  const WaterPixels wl = FindWater(left, boxL), wr = FindWater(right, boxR);
  const double area = (boxL.x1 - boxL.x0) * (boxL.y1 - boxL.y0);
  std::printf("water pixels: left %d (%d inside the block's projection, %.0f px^2), right %d (%d); centroids x %.1f / %.1f\n",
              wl.count, wl.inside, area, wr.count, wr.inside, wl.cx, wr.cx);
  // The water covers most of where the fluid block projects, and almost nothing else.
  EXPECT_GT(wl.count, 0.5 * area) << "left eye: " << wl.count << " water pixels, block " << area;
  EXPECT_GT(wr.count, 0.5 * area) << "right eye: " << wr.count << " water pixels";
  EXPECT_GT(wl.inside, 0.95 * wl.count);
  EXPECT_GT(wr.inside, 0.95 * wr.count);
  // Parallax: the water sits further right in the left eye, by about what the block's centre predicts.
  const double centre[3] = {0.5 * (kWaterMin[0] + kWaterMax[0]), 0.5 * (kWaterMin[1] + kWaterMax[1]),
                            0.5 * (kWaterMin[2] + kWaterMax[2])};
  double xl, yl, xr, yr;
  ASSERT_TRUE(Project(0, centre, &xl, &yl));
  ASSERT_TRUE(Project(1, centre, &xr, &yr));
  const double expected = xl - xr;
  EXPECT_GT(expected, 5.0);
  std::printf("parallax: %.1f px measured, %.1f px predicted for the block's centre\n", wl.cx - wr.cx, expected);
  EXPECT_NEAR(wl.cx - wr.cx, expected, 0.35 * expected) << "left " << wl.cx << ", right " << wr.cx;
  EXPECT_NEAR(wl.cy, wr.cy, 2.0);
}

/// Distance along the view axis (eye-space -z) of a play-space point from one eye of the scripted head.
double EyeDepth(int eye, const double p[3]) {
  const double ex = kHeadX + (eye == 0 ? -0.5 : 0.5) * kIpd;
  const double d[3] = {p[0] - ex, p[1] - kHeadY, p[2] - kHeadZ};
  const double c = std::cos(-kPitch), s = std::sin(-kPitch);
  return -(s * d[1] + c * d[2]);
}

TEST(XrApp, EachEyesDepthReachesTheCompositorWithTheWaterSurfaceInIt) {
  SimHeadset headset("app_depth");
  SetUpHeadset(headset);
  const auto frames = headset.dir / "frames";
  std::filesystem::create_directories(frames);
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_DIR", frames.string());
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_EVERY", "10");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 20" + kCommon,
                            headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  ExpectNoValidationErrors(headset);
  // The runtime's record: every captured frame has a depth layer for both eyes, with the app's planes.
  std::ifstream log(frames / "depth_layers.txt");
  ASSERT_TRUE(log) << "the simulated headset received no depth layer; " << r.out;
  std::string line;
  int layers[2] = {0, 0}, missing = 0;
  double nearZ = 0, farZ = 0;
  while (std::getline(log, line)) {
    std::istringstream ss(line);
    std::string frame, eye, depth, size, nearWord, farWord;
    long index = 0;
    ss >> frame >> index >> eye >> depth >> size;
    if (size == "none") {
      ++missing;
      continue;
    }
    ss >> nearWord >> nearZ >> farWord >> farZ;
    ++layers[eye == "left" ? 0 : 1];
  }
  int captured = 0;
  for (const auto& e : std::filesystem::directory_iterator(frames)) captured += e.path().string().ends_with("_left.png");
  EXPECT_EQ(missing, 0);
  EXPECT_GE(captured, 1);
  EXPECT_EQ(layers[0], captured) << "every captured frame carries the left eye's depth";
  EXPECT_EQ(layers[1], captured);
  ASSERT_GT(farZ, nearZ);
  ASSERT_GT(nearZ, 0.0);

  // The depth image: at the water's pixels, the distance it holds lies on the fluid block (grown by the
  // surface's half spacing, 5 mm): the water wrote its own depth, not the floor's behind it.
  const auto [left, right] = LastPair(frames);
  for (int eye = 0; eye < 2; ++eye) {
    const auto colour = eye == 0 ? left : right;
    std::string raw = colour.string();
    raw.replace(raw.find(".png"), 4, "_depth.f32");
    std::ifstream in(raw, std::ios::binary);
    ASSERT_TRUE(in) << raw;
    std::vector<float> depth(size_t(kEyeW) * kEyeH);
    in.read(reinterpret_cast<char*>(depth.data()), std::streamsize(depth.size() * sizeof(float)));
    ASSERT_TRUE(in);
    int width = 0, height = 0;
    std::vector<uint8_t> px;
    ASSERT_TRUE(ReadPng(colour, &width, &height, &px));
    double lo = 1e9, hi = -1e9;
    for (int i = 0; i < 8; ++i) {
      const double p[3] = {(i & 1) ? kWaterMax[0] + 0.005 : kWaterMin[0] - 0.005,
                           (i & 2) ? kWaterMax[1] + 0.005 : kWaterMin[1] - 0.005,
                           (i & 4) ? kWaterMax[2] + 0.005 : kWaterMin[2] - 0.005};
      lo = std::min(lo, EyeDepth(eye, p)), hi = std::max(hi, EyeDepth(eye, p));
    }
    int water = 0, off = 0;
    for (int y = 0; y < kEyeH; ++y) {
      for (int x = 0; x < kEyeW; ++x) {
        if (!IsWater(&px[(size_t(y) * kEyeW + x) * 4])) continue;
        const double ndc = 2.0 * depth[size_t(y) * kEyeW + x] - 1.0;
        const double distance = 2.0 * nearZ * farZ / (farZ + nearZ - ndc * (farZ - nearZ));
        ++water;
        off += distance < lo - 1e-3 || distance > hi + 1e-3;
      }
    }
    std::printf("eye %d: %d water pixels, %d with a depth off the block (%.3f to %.3f m)\n", eye, water, off, lo, hi);
    EXPECT_GT(water, 100);
    EXPECT_LE(off, water / 50) << "eye " << eye;
  }
}

TEST(XrApp, QualityAutoLowersTheRenderQualityWhenFramesDoNotFitAndFrameStatsTimeEachPass) {
  // llvmpipe draws a frame in tens of milliseconds against the simulated headset's 11 ms period: under
  // --quality auto the render budget lowers the quality, one level per 45 frames, to low.
  SimHeadset headset("app_budget");
  SetUpHeadset(headset);
  headset.env.Set("SPHXR_SIM_XR_EYE_SIZE", "512x512");  // two such eyes take llvmpipe well over 11 ms at any quality
  const auto csv = headset.dir / "frames.csv";
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() +
                                " --frame-limit 100 --quality auto --threads 1 --window-size 160x120 --frame-stats " +
                                csv.string(),
                            headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("render quality high -> medium: frames take"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("render quality medium -> low: frames take"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sphxr --xr: render quality low; GPU per view"), std::string::npos) << r.out;
  std::ifstream in(csv);
  std::string header, line;
  ASSERT_TRUE(std::getline(in, header)) << r.out;
  EXPECT_EQ(header.rfind("frame,interval_ms,render_quality,views,gpu_ms,", 0), 0u) << header;
  for (const char* pass : {"shadow", "opaque", "sky", "water_thickness", "present", "water"}) {
    EXPECT_NE(header.find(std::string(",gpu_") + pass + "_ms"), std::string::npos) << pass << " missing: " << header;
  }
  int rows = 0, high = 0, low = 0;
  double gpu = 0.0;
  while (std::getline(in, line)) {
    ++rows;
    high += line.find(",high,") != std::string::npos;
    low += line.find(",low,") != std::string::npos;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    ASSERT_GE(cells.size(), 5u) << line;
    EXPECT_EQ(cells[3], "2") << "a frame's row sums both eyes: " << line;
    gpu += std::atof(cells[4].c_str());
  }
  EXPECT_GE(rows, 90) << "a row per frame once the first pass times are in";
  EXPECT_GE(high, 40);
  EXPECT_GE(low, 1);
  EXPECT_GT(gpu, 0.0) << "the passes' GPU times are measured";
}

/// The haptic requests of the simulated headset's log for one hand: (amplitude, stop) per line.
std::vector<float> HapticAmplitudes(const std::filesystem::path& log, const std::string& hand) {
  std::vector<float> out;
  std::ifstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    long frame = 0;
    double time = 0;
    std::string who;
    float amplitude = 0;
    if ((ss >> frame >> time >> who >> amplitude) && who == hand) out.push_back(amplitude);
  }
  return out;
}

/// The largest mean fluid speed over the run's snapshots, from the summary line ("(peak X)").
double PeakMeanFluidSpeed(const std::string& out) {
  const size_t p = out.find("mean fluid speed ");
  if (p == std::string::npos) return -1.0;
  const size_t q = out.find("(peak ", p);
  return q == std::string::npos ? -1.0 : std::atof(out.c_str() + q + 6);
}

// A paddle held by the right hand: the default blade on a handle (paddle.h), blade below the grip.
const std::string kRightPaddle = R"(,
  "paddles": { "list": [ { "name": "right paddle", "hand": "right",
    "shapes": [ { "box": { "center": [0.0, -0.05, 0.0], "half_extents": [0.006, 0.05, 0.04] } },
                { "capsule": { "a": [0.0, 0.0, 0.0], "b": [0.0, 0.12, 0.0], "radius": 0.01 } } ],
    "haptics": { "full_scale_force": 2.0, "time_constant": 0.05 } } ] })";

TEST(XrApp, ScriptedControllersPaddleMovesTheWaterAndAsksForHaptics) {
  // The right controller pointing down (grip -z to -y: the paddle upright), its blade 7 cm into the
  // water (surface at y = 1.0 in the play space), sweeping across the tank and back every second.
  const std::string stir =
      "0 right -0.05 1.03 -0.4 -0.7071068 0 0 0.7071068 trigger=1\n"
      "0.5 right 0.05 1.03 -0.4 -0.7071068 0 0 0.7071068 trigger=1\n"
      "1 right -0.05 1.03 -0.4 -0.7071068 0 0 0.7071068 trigger=1\nloop 1\n";
  // The same controller held 0.3 m above the tank: the paddle never touches the water.
  const std::string still = "0 right 0 1.5 -0.4 -0.7071068 0 0 0.7071068 trigger=1\n";
  struct Result {
    AppRun run;
    std::vector<float> right, left;
  };
  auto runWith = [&](const std::string& name, const std::string& poses) {
    SimHeadset headset(name);
    SetUpHeadset(headset, poses);
    const auto haptics = headset.dir / "haptics.txt";
    headset.env.Set("SPHXR_SIM_XR_HAPTICS_LOG", haptics.string());
    Result r;
    // Walls with their own density: water left alone comes to rest (docs/design/walls.md), so the
    // run with the paddle above the water measures only the start's settling. With mirrored walls it
    // keeps a circulation going: peak mean speed 0.056-0.058 m/s against a stirred 0.14-0.15 m/s on
    // one machine (0.29-0.49 on another), too close for 3x.
    r.run = RunSphxr("--xr --scene " + WriteScene(headset.dir, kRightPaddle, "wall_density").string() +
                         " --frame-limit 270 --spacing 0.02 --set stiffness=10000" + kCommon,
                     headset.dir);
    EXPECT_EQ(r.run.code, 0) << r.run.out;
    ExpectNoValidationErrors(headset);
    r.right = HapticAmplitudes(haptics, "right");
    r.left = HapticAmplitudes(haptics, "left");
    return r;
  };
  const Result stirred = runWith("app_paddle_stir", stir);
  const Result held = runWith("app_paddle_still", still);
  const double vStirred = PeakMeanFluidSpeed(stirred.run.out), vHeld = PeakMeanFluidSpeed(held.run.out);
  std::printf("peak mean fluid speed: stirred %.4f m/s, paddle above the water %.4f m/s; right-hand haptic requests: %zu "
              "(peak %.2f), %zu\n",
              vStirred, vHeld, stirred.right.size(),
              stirred.right.empty() ? 0.0f : *std::max_element(stirred.right.begin(), stirred.right.end()),
              held.right.size());
  EXPECT_GT(vStirred, 0.05) << stirred.run.out;
  EXPECT_GT(vStirred, 3.0 * vHeld) << held.run.out;
  // Haptics: the paddle in the water asked for them, the one above the water never did; the left hand
  // holds nothing.
  ASSERT_FALSE(stirred.right.empty()) << stirred.run.out;
  EXPECT_GT(*std::max_element(stirred.right.begin(), stirred.right.end()), 0.05f);
  EXPECT_TRUE(held.right.empty());
  EXPECT_TRUE(stirred.left.empty());
}

TEST(XrApp, MirrorWindowShowsTheLeftEye) {
  SimHeadset headset("app_mirror");
  SetUpHeadset(headset);
  const auto frames = headset.dir / "frames";
  std::filesystem::create_directories(frames);
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_DIR", frames.string());
  const auto mirror = headset.dir / "mirror.png";
  // The window as large as an eye: the blit is 1:1, so the mirror must be the left eye's bytes.
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 5 --quality scene " +
                                "--threads 1 --window-size " + std::to_string(kEyeW) + "x" + std::to_string(kEyeH) +
                                " --screenshot " + mirror.string(),
                            headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto [left, right] = LastPair(frames);
  int w = 0, h = 0, lw = 0, lh = 0;
  std::vector<uint8_t> m, l;
  ASSERT_TRUE(ReadPng(mirror, &w, &h, &m)) << r.out;
  ASSERT_TRUE(ReadPng(left, &lw, &lh, &l));
  ASSERT_EQ(w, lw);
  ASSERT_EQ(h, lh);
  double diff = 0;
  for (size_t i = 0; i < m.size(); ++i)
    if (i % 4 != 3) diff += std::abs(int(m[i]) - int(l[i]));
  diff /= 3.0 * w * h;
  std::printf("mirror against the left eye: mean |difference| %.3f per channel\n", diff);
  EXPECT_LT(diff, 1.0);  // the same bytes (no second sRGB encoding or decoding in the blit)
  ExpectNoValidationErrors(headset);
}

TEST(XrApp, ResetButtonRestartsTheScene) {
  SimHeadset headset("app_reset");
  // The right controller's menu button (the simple controller's reset) pressed from 0.1 s on: one press.
  SetUpHeadset(headset, "0 right 0.3 0.8 0.1 0 0 0 1\n0.1 right 0.3 0.8 0.1 0 0 0 1 menu=1\n");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 20" + kCommon,
                            headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "reset button: the scene starts again"), 1) << r.out;
  ExpectNoValidationErrors(headset);
}

// The headset's display period is the simulation's frame: a runtime displaying at 72 Hz makes the
// scene's 90 Hz frame 1/72 s, said once in the log.
TEST(XrApp, TheFrameFollowsTheHeadsetsDisplayRate) {
  SimHeadset headset("app_frame_rate");
  SetUpHeadset(headset);
  headset.env.Set("SPHXR_SIM_XR_RATE_HZ", "72");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 20" + kCommon,
                            headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "frame: 72.00 Hz, the display's rate (the scene's paddles.frame_rate is 90 Hz)"), 1) << r.out;
  ExpectNoValidationErrors(headset);
}

// --load-state in the headset: the session starts from a state a headless run saved (the same scene,
// its spacing from the file); a file that is not a state file is one line before any session starts.
TEST(XrApp, StartsFromAStateFile) {
  SimHeadset headset("app_state");
  SetUpHeadset(headset);
  const std::string scene = WriteScene(headset.dir).string();
  const std::string state = (headset.dir / "tank.state").string();
  const AppRun saved = RunSphxr("--headless --scene " + scene + " --steps 10 --threads 1 --no-progress --save-state " + state,
                                headset.dir);
  ASSERT_EQ(saved.code, 0) << saved.out;
  const AppRun r = RunSphxr("--xr --scene " + scene + " --frame-limit 5 --load-state " + state + kCommon, headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "started from " + state), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "starting from the scene instead"), 0) << r.out;
  ExpectNoValidationErrors(headset);

  const AppRun bad = RunSphxr("--xr --scene " + scene + " --frame-limit 5 --load-state " + scene + kCommon, headset.dir);
  EXPECT_EQ(bad.code, 1) << bad.out;
  EXPECT_EQ(CountOf(bad.out, "not an sphxr state file"), 1) << bad.out;
  EXPECT_EQ(CountOf(bad.out, "desktop"), 0) << "no fallback to the window for a bad file:\n" << bad.out;
}

// The save button (Touch: right B) writes the running water to --save-state's file between two steps,
// once per press, and a headless run continues from it. The right controller buzzes when the save is
// done (the hands are away from the water, so no paddle asks for haptics).
TEST(XrApp, SaveButtonSavesTheWaterAndARunContinuesFromIt) {
  SimHeadset headset("app_save");
  headset.env.Set("SPHXR_SIM_XR_PROFILE", "oculus/touch_controller");
  const auto haptics = headset.dir / "haptics.txt";
  headset.env.Set("SPHXR_SIM_XR_HAPTICS_LOG", haptics.string());
  SetUpHeadset(headset, "0 right 0.3 0.8 0.1 0 0 0 1\n0.1 right 0.3 0.8 0.1 0 0 0 1 b=1\n");
  const std::string scene = WriteScene(headset.dir).string();
  const std::string state = (headset.dir / "saved.state").string();
  const AppRun r = RunSphxr("--xr --scene " + scene + " --frame-limit 20 --save-state " + state + kCommon, headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "save button: saving the water"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "state saved to " + state), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "reset button"), 0) << "B is not the reset (A):\n" << r.out;
  EXPECT_EQ(CountOf(r.out, "honoured by"), 0) << "--xr honours --save-state:\n" << r.out;
  ASSERT_TRUE(std::filesystem::exists(state));
  ExpectNoValidationErrors(headset);
  // The log: "frame time_s hand amplitude duration_ns frequency_hz [stop]".
  std::stringstream logFile;
  logFile << std::ifstream(haptics).rdbuf();
  const std::string logText = logFile.str();
  std::istringstream log(logText);
  int buzzes = 0, left = 0, other = 0;
  double firstBuzz = -1.0;
  for (std::string line; std::getline(log, line);) {
    std::istringstream in(line);
    long long frame = 0;
    double time = 0.0, amplitude = 0.0;
    std::string hand;
    in >> frame >> time >> hand >> amplitude;
    if (line.empty() || line[0] == '#' || line.find("stop") != std::string::npos) continue;
    if (hand == "left") ++left;
    else if (std::abs(amplitude - 0.8) < 1e-6) {
      ++buzzes;
      if (firstBuzz < 0.0) firstBuzz = time;
    } else ++other;
  }
  EXPECT_GE(buzzes, 1) << "the save is felt on the right controller";
  EXPECT_GE(firstBuzz, 0.1) << "after the press at 0.1 s, not before";
  EXPECT_EQ(left, 0);
  EXPECT_EQ(other, 0) << "no other haptics: the paddles are out of the water\n" << logText;
  const AppRun next = RunSphxr("--headless --scene " + scene + " --steps 3 --threads 1 --no-progress --load-state " + state,
                               headset.dir);
  ASSERT_EQ(next.code, 0) << next.out;
  EXPECT_EQ(CountOf(next.out, "started from " + state), 1) << next.out;
  EXPECT_EQ(CountOf(next.out, "of the whole run"), 1) << "the file has the headset run's step count:\n" << next.out;
}

TEST(XrApp, DefaultModeIsTheHeadsetWhenARuntimeAnswers) {
  SimHeadset headset("app_default");
  SetUpHeadset(headset);
  const AppRun r = RunSphxr("--scene " + WriteScene(headset.dir).string() + " --frame-limit 5" + kCommon, headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("sphxr --xr: OpenXR session ended after 5 frames"), std::string::npos) << r.out;
  ExpectNoValidationErrors(headset);
}

TEST(XrApp, NoRuntimeIsOneLineThenTheDesktopWindow) {
  const auto dir = TempDir("app_noruntime");
  ScopedEnv env;
  env.Set("XR_RUNTIME_JSON", (dir / "missing_runtime.json").string());
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(dir).string() + " --frame-limit 3" + kCommon, dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "OpenXR"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "no OpenXR runtime available"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "sphxr --xr:"), 0) << r.out;  // no session summary: none ran
  // A manifest whose runtime library is missing: the same one line.
  std::ofstream(dir / "broken_runtime.json")
      << R"({"file_format_version": "1.0.0", "runtime": {"name": "broken", "library_path": "./libmissing.so"}})";
  env.Set("XR_RUNTIME_JSON", (dir / "broken_runtime.json").string());
  const AppRun b = RunSphxr("--xr --scene " + WriteScene(dir).string() + " --frame-limit 3" + kCommon, dir);
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(CountOf(b.out, "OpenXR"), 1) << b.out;
  EXPECT_EQ(CountOf(b.out, "using the desktop window"), 1) << b.out;
  // Without a mode flag, no runtime is not even worth a line: the desktop window is the default.
  const AppRun d = RunSphxr("--scene " + WriteScene(dir).string() + " --frame-limit 3" + kCommon, dir);
  ASSERT_EQ(d.code, 0) << d.out;
  EXPECT_EQ(CountOf(d.out, "OpenXR"), 0) << d.out;
}

TEST(XrApp, RuntimeFailingAtSessionCreationIsOneLineThenTheDesktopWindow) {
  SimHeadset headset("app_failsession");
  headset.env.Set("SPHXR_SIM_XR_FAIL_SESSION", "1");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 3" + kCommon,
                         headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "xrCreateSession"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
}

TEST(XrApp, NoDisplayIsOneLineThenHeadless) {
  const auto dir = TempDir("app_nodisplay");
  ScopedEnv env;
  env.Set("XR_RUNTIME_JSON", SPHXR_SIM_RUNTIME_JSON);
  env.Set("DISPLAY", "");
  env.Set("WAYLAND_DISPLAY", "");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(dir).string() + " --time 0.005 --threads 1", dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "running headless"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "display"), 1) << r.out;
}

TEST(XrApp, SessionLostMidRunEndsCleanlyInTheDesktopWindow) {
  SimHeadset headset("app_lost");
  SetUpHeadset(headset);
  headset.env.Set("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", "10");
  const AppRun r = RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 20" + kCommon,
                         headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "the XR session was lost"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
  EXPECT_NE(r.out.find("sphxr --xr: session states IDLE READY SYNCHRONIZED VISIBLE FOCUSED LOSS_PENDING\n"),
            std::string::npos)
      << r.out;
  ExpectNoValidationErrors(headset);
  // The water stirred in the headset is not lost: saved beside the save button's file, and the window
  // continues from it.
  const std::filesystem::path lost = headset.dir / "xr_test_tank-lost.state";
  EXPECT_TRUE(std::filesystem::exists(lost)) << r.out;
  EXPECT_NE(r.out.find("the window continues from the headset's water (xr_test_tank-lost.state)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("started from xr_test_tank-lost.state"), std::string::npos) << r.out;
  // Lost after the frame limit's worth of frames: nothing left to show, the program exits.
  SimHeadset again("app_lost_end");
  SetUpHeadset(again);
  again.env.Set("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", "5");
  const AppRun e = RunSphxr("--xr --scene " + WriteScene(again.dir).string() + " --frame-limit 5" + kCommon, again.dir);
  ASSERT_EQ(e.code, 0) << e.out;
  EXPECT_EQ(CountOf(e.out, "the XR session was lost"), 1) << e.out;
  EXPECT_EQ(CountOf(e.out, "exiting"), 1) << e.out;
  // The instance lost instead of the session: the same clean end.
  SimHeadset instance("app_lost_instance");
  SetUpHeadset(instance);
  instance.env.Set("SPHXR_SIM_XR_LOSE_INSTANCE_AFTER_FRAMES", "5");
  const AppRun i = RunSphxr("--xr --scene " + WriteScene(instance.dir).string() + " --frame-limit 10" + kCommon,
                            instance.dir);
  ASSERT_EQ(i.code, 0) << i.out;
  EXPECT_EQ(CountOf(i.out, "the XR session was lost"), 1) << i.out;
  EXPECT_EQ(CountOf(i.out, "using the desktop window"), 1) << i.out;
}

}  // namespace
}  // namespace sphxr::xr::test
