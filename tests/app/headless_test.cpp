// The command line (ParseCommandLine) and the headless runner end to end: the real sphxr binary
// (SPHXR_BINARY) on a small scene, its summary, stats CSV and PLY exports; bad input exits cleanly.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "sphxr/app/cli.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/headless.h"
#include "sphxr/common/log.h"
#include "sphxr/app/state_file.h"
#include "sphxr/app/scene_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

Status Parse(std::vector<std::string> args, Options* out) {
  args.insert(args.begin(), "sphxr");
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  return ParseCommandLine(static_cast<int>(argv.size()), argv.data(), out);
}

std::string Join(const std::vector<std::string>& args) {
  std::string s;
  for (const std::string& a : args) s += (s.empty() ? "" : " ") + a;
  return s;
}

TEST(CommandLineTest, AcceptsEveryFlag) {
  Options o;
  const std::vector<std::string> args = {
      "--headless", "--scene", "x.json", "--steps", "20", "--device", "cpu", "--threads", "2", "--spacing", "0.01",
      "--set", "stiffness=1e5", "--set", "cfl=0.3", "--export-every", "10", "--out", "dir", "--export-format", "vtk",
      "--stats", "s.csv", "--validate", "--no-progress", "--settle", "2.5", "--load-state", "in.state",
      "--save-state", "out.state"};
  const Status s = Parse(args, &o);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(o.mode, Mode::kHeadless);
  EXPECT_EQ(o.scenePath, "x.json");
  EXPECT_EQ(o.steps, 20);
  EXPECT_EQ(o.time, 0.0);
  EXPECT_EQ(o.device, sim::Device::kCpu);
  EXPECT_EQ(o.threads, 2);
  EXPECT_FLOAT_EQ(o.spacing, 0.01f);
  EXPECT_EQ(o.sets, (std::vector<std::string>{"stiffness=1e5", "cfl=0.3"}));
  EXPECT_EQ(o.exportEvery, 10);
  EXPECT_EQ(o.outDir, "dir");
  EXPECT_EQ(o.exportFormat, "vtk");
  EXPECT_EQ(o.statsPath, "s.csv");
  EXPECT_TRUE(o.validate);
  EXPECT_EQ(o.progress, 0);
  EXPECT_DOUBLE_EQ(o.settle, 2.5);
  EXPECT_EQ(o.loadState, "in.state");
  EXPECT_EQ(o.saveState, "out.state");
  EXPECT_FALSE(o.help);

  ASSERT_TRUE(Parse({"--time", "0.5", "--device", "cuda", "--progress"}, &o).ok());
  EXPECT_DOUBLE_EQ(o.time, 0.5);
  EXPECT_EQ(o.steps, 0);
  EXPECT_EQ(o.device, sim::Device::kCuda);
  EXPECT_EQ(o.progress, 1);
  EXPECT_EQ(o.mode, Mode::kAuto);
  ASSERT_TRUE(Parse({"--device", "auto"}, &o).ok());
  EXPECT_EQ(o.device, sim::Device::kAuto);
  ASSERT_TRUE(Parse({"--help"}, &o).ok());
  EXPECT_TRUE(o.help);
  ASSERT_TRUE(Parse({"-h"}, &o).ok());
  EXPECT_TRUE(o.help);
  ASSERT_TRUE(Parse({"--desktop"}, &o).ok());
  EXPECT_EQ(o.mode, Mode::kDesktop);
  ASSERT_TRUE(Parse({"--xr"}, &o).ok());
  EXPECT_EQ(o.mode, Mode::kXr);
}

TEST(CommandLineTest, EveryModeLoadsTheSceneWithTheSameOverrides) {
  // LoadSceneWithOptions is what the headless runner, the window and --xr start from: a --reuse preset
  // replaces the scene's reuse parameters, --set then overrides one of them, --spacing the spacing.
  Options o;
  ASSERT_TRUE(Parse({"--scene", SPHXR_SCENES_DIR "/dam_break.json", "--reuse", "balanced", "--set", "reuse.idle=2",
                     "--set", "stiffness=123456", "--spacing", "0.02"},
                    &o)
                  .ok());
  SceneFile scene;
  const Status s = LoadSceneWithOptions(o, &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  sim::ReuseParams balanced;
  ASSERT_TRUE(sim::ApplyReusePreset("balanced", &balanced));
  EXPECT_TRUE(scene.setup.reuse.enabled);
  EXPECT_FLOAT_EQ(scene.setup.reuse.threshold, balanced.threshold);
  EXPECT_EQ(scene.setup.reuse.idle, 2) << "--set comes after the preset";
  EXPECT_FLOAT_EQ(scene.setup.params.stiffness, 123456.0f);
  EXPECT_FLOAT_EQ(scene.setup.params.spacing, 0.02f);

  ASSERT_TRUE(Parse({"--scene", SPHXR_SCENES_DIR "/dam_break.json", "--reuse", "balanced", "--set", "nonsense=1"}, &o).ok());
  const Status bad = LoadSceneWithOptions(o, &scene);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("nonsense"), std::string::npos) << bad.message();
}

TEST(CommandLineTest, DefaultsWhenNothingIsGiven) {
  Options o;
  ASSERT_TRUE(Parse({}, &o).ok());
  EXPECT_EQ(o.mode, Mode::kAuto);
  EXPECT_EQ(o.device, sim::Device::kAuto);
  EXPECT_EQ(o.threads, 0);
  EXPECT_EQ(o.exportFormat, "ply");
  EXPECT_EQ(o.progress, -1);
  EXPECT_FALSE(o.validate);
  EXPECT_LT(o.settle, 0.0) << "the scene's run.settle";
  // the default scene is the dam break, and it exists
  EXPECT_EQ(std::filesystem::path(o.scenePath).filename(), "dam_break.json");
  EXPECT_TRUE(std::filesystem::exists(o.scenePath)) << o.scenePath;
}

TEST(CommandLineTest, AScenesNameIsFoundAndANameFoundNowhereIsRefusedWhenRead) {
  Options o;
  ASSERT_TRUE(Parse({"--scene", "stir"}, &o).ok());
  EXPECT_EQ(std::filesystem::path(o.scenePath), std::filesystem::path(SPHXR_SCENES_DIR) / "stir.json");
  // The command line names the scene; reading it says where a name was looked for.
  ASSERT_TRUE(Parse({"--scene", "no_such_scene"}, &o).ok());
  EXPECT_EQ(o.scenePath, "no_such_scene");
  SceneFile scene;
  const Status s = LoadSceneWithOptions(o, &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("--scene no_such_scene: no scene of that name (nor with .json) in the current "
                             "directory, " SPHXR_SCENES_DIR),
            std::string::npos)
      << s.message();
  // A path is read as it is: the loader's own message.
  ASSERT_TRUE(Parse({"--scene", "/nonexistent/scene.json"}, &o).ok());
  const Status path = LoadSceneWithOptions(o, &scene);
  ASSERT_FALSE(path.ok());
  EXPECT_NE(path.message().find("/nonexistent/scene.json"), std::string::npos) << path.message();
  EXPECT_EQ(path.message().find("no scene"), std::string::npos) << path.message();
}

TEST(CommandLineTest, EveryFlagInTheUsageTextIsAccepted) {
  // Values for the documented flags that take one; a flag missing here and taking a value fails below.
  const std::map<std::string, std::string> values = {
      {"--scene", "a.json"}, {"--time", "1"},         {"--steps", "5"},          {"--settle", "2"},          {"--device", "cpu"},
      {"--load-state", "a.state"}, {"--save-state", "b.state"},
      {"--threads", "1"},    {"--spacing", "0.01"},   {"--set", "cfl=0.3"},      {"--export-every", "2"},
      {"--out", "d"},        {"--export-format", "ply"}, {"--stats", "f.csv"}, {"--reuse", "on"},
      {"--export-surface-every", "3"}, {"--surface-format", "obj"},
      {"--screenshot", "a.png"}, {"--frames", "d"}, {"--fps", "30"}, {"--image-size", "64x48"},
      {"--window-size", "640x480"}, {"--frame-limit", "3"}, {"--render", "particles"}, {"--quality", "auto"},
      {"--checkpoint-every", "0.1"}, {"--checkpoint-keep", "3"}, {"--export-interval", "0.01"},
      {"--export-surface-interval", "0.02"}, {"--probes", "p.csv"}, {"--render-quality", "low"},
      {"--frame-stats", "f.csv"}};
  const std::string usage = UsageText();
  std::set<std::string> flags;
  const std::regex flag("--[a-z][a-z-]*");
  for (auto it = std::sregex_iterator(usage.begin(), usage.end(), flag); it != std::sregex_iterator(); ++it) {
    flags.insert(it->str());
  }
  EXPECT_GE(flags.size(), 14u) << usage;
  // The options that act only with another (CheckOptionsTakeEffect) are given with it.
  const std::map<std::string, std::vector<std::string>> with = {
      {"--checkpoint-keep", {"--checkpoint-every", "0.1"}}, {"--export-format", {"--export-every", "3"}},
      {"--fps", {"--frames", "d"}}, {"--surface-format", {"--export-surface-every", "3"}}};
  for (const std::string& f : flags) {
    std::vector<std::string> args = {f};
    if (values.count(f)) args.push_back(values.at(f));
    if (with.count(f)) args.insert(args.end(), with.at(f).begin(), with.at(f).end());
    Options o;
    const Status s = Parse(args, &o);
    EXPECT_TRUE(s.ok()) << "documented flag " << f << " refused: " << s.message();
  }
}

void ExpectRejected(const std::vector<std::string>& args, std::initializer_list<std::string> needles) {
  Options o;
  const Status s = Parse(args, &o);
  ASSERT_FALSE(s.ok()) << "accepted: " << Join(args);
  for (const std::string& n : needles) {
    EXPECT_NE(s.message().find(n), std::string::npos) << Join(args) << ": '" << n << "' not in: " << s.message();
  }
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line: " << s.message();
}

TEST(CommandLineTest, RejectsBadValuesNamingTheFlag) {
  ExpectRejected({"--threads", "-1"}, {"--threads", "-1"});
  ExpectRejected({"--threads", "two"}, {"--threads", "not an integer"});
  ExpectRejected({"--threads", "1.5"}, {"--threads"});
  ExpectRejected({"--time", "abc"}, {"--time", "abc", "not a number"});
  ExpectRejected({"--time", "-1"}, {"--time"});
  ExpectRejected({"--time", "nan"}, {"--time"});
  ExpectRejected({"--time", "inf"}, {"--time", "not a finite number"});
  ExpectRejected({"--time", ""}, {"--time"});
  ExpectRejected({"--device", "gpu"}, {"--device", "gpu", "auto, cpu or cuda"});
  ExpectRejected({"--steps", "10", "--time", "1"}, {"--time", "--steps"});
  ExpectRejected({"--time", "1", "--steps", "10"}, {"--time", "--steps"});
  ExpectRejected({"--steps", "0"}, {"--steps"});
  ExpectRejected({"--settle", "-1"}, {"--settle", "0 to 3600"});
  ExpectRejected({"--settle", "nan"}, {"--settle", "not a finite number"});
  ExpectRejected({"--time", "0x10"}, {"--time", "not a decimal number"});  // strtod read it as 16 s
  ExpectRejected({"--load-state", ""}, {"--load-state", "file name"});
  ExpectRejected({"--save-state"}, {"--save-state", "missing value"});
  ExpectRejected({"--steps", "1e3"}, {"--steps"});
  ExpectRejected({"--spacing", "0"}, {"--spacing"});
  ExpectRejected({"--spacing", "-0.01"}, {"--spacing"});
  ExpectRejected({"--export-every", "0"}, {"--export-every"});
  ExpectRejected({"--export-format", "obj"}, {"--export-format", "ply or vtk"});
  ExpectRejected({"--scene"}, {"--scene", "missing value"});
  ExpectRejected({"--headless", "--steps"}, {"--steps", "missing value"});
  ExpectRejected({"--frobnicate"}, {"--frobnicate", "unknown"});
  ExpectRejected({"scene.json"}, {"scene.json"});
}

// ---- the binary end to end ------------------------------------------------------------------------

struct Result {
  int status = -1;  // wait status
  std::string out;
  std::string err;
  bool Exited() const { return WIFEXITED(status); }
  int Code() const { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }
};

std::string Quote(const std::string& s) { return "'" + s + "'"; }

Result RunBinary(const std::string& args, const test::TempDir& dir) {
  Result r;
  const std::string errPath = dir.File("stderr.txt");
  const std::string command = Quote(SPHXR_BINARY) + " " + args + " 2>" + Quote(errPath);
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    ADD_FAILURE() << "popen failed: " << command;
    return r;
  }
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof(buffer), pipe)) r.out.append(buffer, n);
  r.status = pclose(pipe);
  r.err = test::ReadFile(errPath);
  return r;
}

using test::Lines;

std::vector<std::string> Split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, sep)) out.push_back(cell);
  return out;
}

/// A stats CSV's rows without their last six columns, the launch counts: what the process asked of the
/// device (a continued run allocates again at its first step), not the state the rows describe.
std::vector<std::string> WithoutCounts(std::vector<std::string> rows) {
  for (std::string& row : rows) {
    for (int k = 0; k < 6 && row.rfind(',') != std::string::npos; ++k) row.erase(row.rfind(','));
  }
  return rows;
}

// 10 x 10 x 10 = 1000 fluid particles at 0.01 m in a 0.2 x 0.2 x 0.1 m tank.
const char* kSmallScene = R"({
  "name": "headless_e2e",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } ],
  "run": { "steps": 5 }
})";
constexpr int kSmallSceneParticles = 1000;

struct Ply {
  std::vector<std::string> header;
  size_t vertices = 0;
  std::vector<std::string> properties;  // names, in order
  std::vector<std::string> types;
  size_t headerBytes = 0;
  std::string body;
};

Ply ReadPly(const std::string& path) {
  Ply ply;
  const std::string data = test::ReadFile(path);
  const size_t end = data.find("end_header\n");
  if (end == std::string::npos) return ply;
  ply.headerBytes = end + std::strlen("end_header\n");
  ply.header = Lines(data.substr(0, end));
  for (const std::string& line : ply.header) {
    const std::vector<std::string> w = Split(line, ' ');
    if (w.size() == 3 && w[0] == "element" && w[1] == "vertex") ply.vertices = std::stoul(w[2]);
    if (w.size() == 3 && w[0] == "property") {
      ply.types.push_back(w[1]);
      ply.properties.push_back(w[2]);
    }
  }
  ply.body = data.substr(ply.headerBytes);
  return ply;
}

TEST(HeadlessTest, RunsASmallSceneWithStatsAndExports) {
  test::TempDir dir("headless");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string csv = dir.File("stats.csv");
  const std::string out = dir.File("frames");
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 20 --stats " + Quote(csv) +
                                 " --export-every 10 --out " + Quote(out) + " --threads 1 --no-progress",
                             dir);
  ASSERT_TRUE(r.Exited()) << "sphxr did not exit normally (signal?), status " << r.status << "\nstderr:\n" << r.err;
  ASSERT_EQ(r.Code(), 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;

  // summary
  EXPECT_NE(r.out.find("sphxr summary"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("particles lost  0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(std::to_string(kSmallSceneParticles) + " fluid"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("steps           20"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("exported        3 files"), std::string::npos) << r.out;

  // stats CSV: the documented header and one row per step
  const std::vector<std::string> lines = Lines(test::ReadFile(csv));
  ASSERT_EQ(lines.size(), 21u) << "header + 20 steps expected in " << csv;
  const std::vector<std::string> header = Split(lines[0], ',');
  EXPECT_EQ(lines[0], "step,time,dt,max_speed,mean_density_error,max_density_error,clamped,active_fraction,"
                      "launches,host_waits,allocations,copies_back,copies_back_unasked,uploads");
  double timeSum = 0.0;
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> cells = Split(lines[i], ',');
    ASSERT_EQ(cells.size(), header.size()) << "row " << i << ": " << lines[i];
    std::vector<double> v;
    for (const std::string& c : cells) {
      char* end = nullptr;
      v.push_back(std::strtod(c.c_str(), &end));
      ASSERT_TRUE(!c.empty() && *end == '\0' && std::isfinite(v.back())) << "row " << i << ": '" << c << "'";
    }
    EXPECT_EQ(v[0], static_cast<double>(i)) << "step column";
    EXPECT_GT(v[2], 0.0) << "dt of row " << i;
    timeSum += v[2];
    EXPECT_NEAR(v[1], timeSum, 1e-5 * timeSum) << "time must be the running sum of dt, row " << i;
    EXPECT_GE(v[3], 0.0);
    EXPECT_GE(v[5], 0.0);
    EXPECT_GE(v[6], 0.0);
  }

  // PLY exports at steps 0, 10, 20, each declaring the particle count, with a body of that many vertices
  for (int step : {0, 10, 20}) {
    char name[64];
    std::snprintf(name, sizeof(name), "particles_%06d.ply", step);
    const std::string path = (std::filesystem::path(out) / name).string();
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    const Ply ply = ReadPly(path);
    ASSERT_FALSE(ply.header.empty()) << path << " has no PLY header";
    EXPECT_EQ(ply.header[0], "ply");
    EXPECT_EQ(ply.header[1], "format binary_little_endian 1.0");
    EXPECT_EQ(ply.vertices, static_cast<size_t>(kSmallSceneParticles)) << path;
    ASSERT_GE(ply.properties.size(), 3u);
    EXPECT_EQ(ply.properties[0], "x");
    EXPECT_EQ(ply.properties[1], "y");
    EXPECT_EQ(ply.properties[2], "z");
    for (const std::string& t : ply.types) ASSERT_TRUE(t == "float" || t == "uint" || t == "int") << t;
    const size_t stride = 4 * ply.properties.size();
    ASSERT_EQ(ply.body.size(), ply.vertices * stride) << path << ": body size does not match the header";
    // the vertices: positions inside the tank, ids a permutation of 0..n-1
    size_t idColumn = ply.properties.size();
    for (size_t c = 0; c < ply.properties.size(); ++c)
      if (ply.properties[c] == "id") idColumn = c;
    ASSERT_LT(idColumn, ply.properties.size()) << "no id property";
    std::vector<int> seen(ply.vertices, 0);
    for (size_t i = 0; i < ply.vertices; ++i) {
      float p[3];
      std::memcpy(p, ply.body.data() + i * stride, sizeof(p));
      ASSERT_TRUE(p[0] >= 0 && p[0] <= 0.2f && p[1] >= 0 && p[1] <= 0.2f && p[2] >= 0 && p[2] <= 0.1f)
          << path << " vertex " << i << " at [" << p[0] << ", " << p[1] << ", " << p[2] << "]";
      uint32_t id;
      std::memcpy(&id, ply.body.data() + i * stride + 4 * idColumn, sizeof(id));
      ASSERT_LT(id, ply.vertices) << path;
      ++seen[id];
    }
    for (size_t id = 0; id < seen.size(); ++id) ASSERT_EQ(seen[id], 1) << path << ": id " << id;
  }
}

TEST(HeadlessTest, DfsphStatsCarryTheSolvesIterationsAndErrors) {
  test::TempDir dir("headless_dfsph");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string csv = dir.File("stats.csv");
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 10 --set method=dfsph --stats " +
                                 Quote(csv) + " --threads 1 --no-progress",
                             dir);
  ASSERT_TRUE(r.Exited()) << r.err;
  ASSERT_EQ(r.Code(), 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
  const std::vector<std::string> lines = Lines(test::ReadFile(csv));
  ASSERT_EQ(lines.size(), 11u);
  EXPECT_EQ(lines[0], "step,time,dt,max_speed,mean_density_error,max_density_error,clamped,active_fraction,"
                      "density_iterations,divergence_iterations,solver_density_error,solver_divergence_error,"
                      "launches,host_waits,allocations,copies_back,copies_back_unasked,uploads");
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> cells = Split(lines[i], ',');
    ASSERT_EQ(cells.size(), 18u) << "row " << i << ": " << lines[i];
    EXPECT_EQ(cells[0], std::to_string(i)) << "row " << i << ": " << lines[i];
    EXPECT_GE(std::stoi(cells[8]), 2) << "at least min_iterations density iterations: " << lines[i];
    EXPECT_LE(std::stod(cells[10]), 0.01 * sim::SolverParams{}.densityTolerance)
        << "the density solve's error within its default tolerance: " << lines[i];
  }
}

TEST(HeadlessTest, ExportsTheSurfaceAsPlyAndObj) {
  // The small scene with a surface section: a finer lattice than the spacing.
  std::string text = kSmallScene;
  text.insert(text.rfind('}'), R"(, "surface": { "cell_size": 0.005, "iso_level": 0.5 })");
  test::TempDir dir("surface");
  const std::string scene = dir.Write("scene.json", text);
  for (const std::string format : {"ply", "obj"}) {
    const std::string out = dir.File("surface_" + format);
    const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 6 --export-surface-every 3 --surface-format " +
                                   format + " --out " + Quote(out) + " --threads 1 --no-progress",
                               dir);
    ASSERT_TRUE(r.Exited()) << r.err;
    ASSERT_EQ(r.Code(), 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
    EXPECT_NE(r.out.find("surface         3 meshes"), std::string::npos) << r.out;
    for (int step : {0, 3, 6}) {
      char name[64];
      std::snprintf(name, sizeof(name), "surface_%06d.%s", step, format.c_str());
      const std::string path = (std::filesystem::path(out) / name).string();
      ASSERT_TRUE(std::filesystem::exists(path)) << path;
      std::vector<float> positions, normals;
      size_t faces = 0;
      if (format == "ply") {
        const Ply ply = ReadPly(path);
        ASSERT_EQ(ply.properties, (std::vector<std::string>{"x", "y", "z", "nx", "ny", "nz"}));  // (the face list has 5 words)
        for (const std::string& line : ply.header) {
          const std::vector<std::string> w = Split(line, ' ');
          if (w.size() == 3 && w[0] == "element" && w[1] == "face") faces = std::stoul(w[2]);
        }
        ASSERT_EQ(ply.body.size(), ply.vertices * 24 + faces * 13) << path;
        ASSERT_EQ(ply.vertices, 3 * faces);
        for (size_t v = 0; v < ply.vertices; ++v) {
          float f[6];
          std::memcpy(f, ply.body.data() + 24 * v, sizeof(f));
          positions.insert(positions.end(), f, f + 3);
          normals.insert(normals.end(), f + 3, f + 6);
        }
        for (size_t t = 0; t < faces; ++t) {  // the soup: face t is vertices 3t, 3t+1, 3t+2
          const char* rec = ply.body.data() + 24 * ply.vertices + 13 * t;
          uint32_t idx[3];
          std::memcpy(idx, rec + 1, sizeof(idx));
          ASSERT_EQ(rec[0], 3);
          ASSERT_EQ(idx[0], 3 * t);
          ASSERT_EQ(idx[2], 3 * t + 2);
        }
      } else {
        for (const std::string& line : Lines(test::ReadFile(path))) {
          const std::vector<std::string> w = Split(line, ' ');
          if (w.size() == 4 && w[0] == "v") for (int c = 1; c < 4; ++c) positions.push_back(std::stof(w[c]));
          if (w.size() == 4 && w[0] == "vn") for (int c = 1; c < 4; ++c) normals.push_back(std::stof(w[c]));
          if (w.size() == 4 && w[0] == "f") ++faces;
        }
        ASSERT_EQ(positions.size(), 9 * faces);
        ASSERT_EQ(normals.size(), positions.size());
      }
      // A closed blob of water around the 0.1 m cube: hundreds of triangles, inside the tank's reach,
      // unit normals.
      EXPECT_GT(faces, 500u) << path;
      for (size_t v = 0; v < positions.size() / 3; ++v) {
        const float* p = &positions[3 * v];
        ASSERT_TRUE(p[0] > -0.05f && p[0] < 0.25f && p[1] > -0.05f && p[1] < 0.25f && p[2] > -0.05f && p[2] < 0.15f) << path;
        const float* n = &normals[3 * v];
        ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0f, 1e-3f) << path;
      }
    }
  }
}

/// A bad scene: exits non-zero (not by a signal), prints nothing on stdout, and one line on stderr that
/// contains every needle.
void ExpectCleanFailure(const std::string& content, std::initializer_list<std::string> needles) {
  test::TempDir dir("badscene");
  const std::string scene = dir.Write("bad_scene.json", content);
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 5 --threads 1 --no-progress", dir);
  ASSERT_TRUE(r.Exited()) << "crashed: status " << r.status << "\nstderr:\n" << r.err;
  EXPECT_NE(r.Code(), 0) << "a bad scene must fail; stdout:\n" << r.out;
  EXPECT_EQ(r.out.find("sphxr summary"), std::string::npos) << r.out;
  const std::vector<std::string> lines = Lines(r.err);
  ASSERT_EQ(lines.size(), 1u) << "expected a one-line error, got:\n" << r.err;
  EXPECT_NE(lines[0].find(scene), std::string::npos) << "must name the file: " << lines[0];
  for (const std::string& n : needles) EXPECT_NE(lines[0].find(n), std::string::npos) << "'" << n << "' not in: " << lines[0];
}

TEST(HeadlessTest, InvalidJsonFailsCleanly) { ExpectCleanFailure("{ \"tank\": [0, 0, ", {"not valid JSON"}); }

TEST(HeadlessTest, NegativeSpacingFailsCleanly) {
  ExpectCleanFailure(R"({ "solver": { "spacing": -0.01 }, "tank": { "min": [0,0,0], "max": [1,1,1] },
                          "fluid": [ { "min": [0,0,0], "max": [0.5,0.5,0.5] } ] })",
                     {"solver.spacing"});
}

TEST(HeadlessTest, FluidOutsideTheTankFailsCleanly) {
  ExpectCleanFailure(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.2] },
                          "fluid": [ { "min": [0,0,0], "max": [0.5,0.1,0.1] } ] })",
                     {"fluid[0]"});
}

// Overlapping blocks would give particles at the same place (twins with no force between them, which
// never separate); touching blocks are fine.
TEST(HeadlessTest, OverlappingFluidBlocksFailCleanly) {
  ExpectCleanFailure(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.2] },
                          "fluid": [ { "min": [0,0,0], "max": [0.1,0.1,0.1] },
                                     { "min": [0.08,0,0], "max": [0.15,0.1,0.1] } ] })",
                     {"fluid[1]", "overlaps fluid[0]"});
}

// A failed run whose whole stderr is one line containing `needle`; `code` the exit code (0: any but 0).
void ExpectOneLineError(const Result& r, const std::string& needle, int code = 0, const char* why = "") {
  ASSERT_TRUE(r.Exited()) << "crashed: status " << r.status << "\nstderr:\n" << r.err;
  if (code == 0) {
    EXPECT_NE(r.Code(), 0);
  } else {
    EXPECT_EQ(r.Code(), code);
  }
  const std::vector<std::string> lines = Lines(r.err);
  ASSERT_EQ(lines.size(), 1u) << why << r.err;
  EXPECT_NE(lines[0].find(needle), std::string::npos) << lines[0];
}

TEST(HeadlessTest, MissingSceneFileFailsCleanly) {
  test::TempDir dir("missing");
  const std::string scene = dir.File("does_not_exist.json");
  ExpectOneLineError(RunBinary("--headless --scene " + Quote(scene) + " --steps 5", dir), scene);
}

TEST(HeadlessTest, BadFlagFailsWithUsageHint) {
  test::TempDir dir("badflag");
  ExpectOneLineError(RunBinary("--headless --threads -1", dir), "--threads");
}

TEST(HeadlessTest, SceneThatIsADirectoryFailsCleanly) {
  test::TempDir dir("scenedir");
  ExpectOneLineError(RunBinary("--headless --scene " + Quote(dir.path().string()) + " --steps 5", dir), "is a directory");
}

// Every mode loads the scene first: a window must not call a bad scene "window unavailable" and then
// repeat the error from the headless fallback (with or without a display).
TEST(HeadlessTest, DesktopWithABadSceneIsOneError) {
  test::TempDir dir("desktopbad");
  const std::string scene = dir.Write("bad.json", "hello");
  ExpectOneLineError(RunBinary("--desktop --scene " + Quote(scene) + " --frame-limit 3", dir), "not valid JSON", 1);
}

// A full disk (/dev/full) must fail the run, not print a summary over a CSV that was never written.
TEST(HeadlessTest, StatsThatCannotBeWrittenFailTheRun) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  test::TempDir dir("statsfull");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 3 --stats /dev/full --threads 1 --no-progress", dir);
  ASSERT_TRUE(r.Exited());
  EXPECT_EQ(r.Code(), 1);
  EXPECT_EQ(r.out.find("sphxr summary"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("--stats /dev/full: write failed"), std::string::npos) << r.err;
}

// A scene or trajectory "file" that never ends (/dev/zero) is refused at its size limit, in a moment,
// instead of being read until the kernel kills the process; a directory as a trajectory is named so.
TEST(HeadlessTest, EndlessOrDirectoryInputsFailCleanly) {
  if (!std::filesystem::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  test::TempDir dir("endless");
  ExpectOneLineError(RunBinary("--headless --steps 1 --scene /dev/zero", dir), "/dev/zero: not a regular file");
  std::string stir = test::ReadFile(SPHXR_SCENES_DIR "/stir.json");
  const size_t at = stir.find("stir_paddle.csv");
  ASSERT_NE(at, std::string::npos);
  const std::string endless = dir.Write("endless.json", std::string(stir).replace(at, 15, "/dev/zero"));
  ExpectOneLineError(RunBinary("--headless --steps 1 --scene " + Quote(endless), dir),
                     "/dev/zero: not a regular file");
  // (Put together, not replace(at, 15, "."): GCC 12's -Wrestrict misfires on that shrinking replace.)
  const std::string directory = dir.Write("directory.json", stir.substr(0, at) + "." + stir.substr(at + 15));
  ExpectOneLineError(RunBinary("--headless --steps 1 --scene " + Quote(directory), dir), "is a directory");
}

// So must a particle export that does not reach the disk (a small file used to sit in stdio's buffer
// past the error check, and fclose's failure was ignored).
TEST(HeadlessTest, ExportThatCannotBeWrittenFailsTheRun) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  test::TempDir dir("exportfull");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::filesystem::path out = dir.path() / "out";
  std::filesystem::create_directories(out);
  std::filesystem::create_symlink("/dev/full", out / "particles_000002.ply");
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 3 --export-every 2 --out " +
                                 Quote(out.string()) + " --threads 1 --no-progress",
                             dir);
  ASSERT_TRUE(r.Exited());
  EXPECT_EQ(r.Code(), 1);
  EXPECT_NE(r.err.find("particles_000002.ply: write failed"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::is_symlink(out / "particles_000002.ply")) << "a device behind a failed export stays";
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/full"));
}

// The screenshot is written after the run; a place it cannot go is refused before the run costs anything.
TEST(HeadlessTest, ScreenshotIntoAMissingDirectoryRefusedBeforeTheRun) {
  test::TempDir dir("shotdir");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string shot = (dir.path() / "missing" / "x.png").string();
  ExpectOneLineError(RunBinary("--headless --scene " + Quote(scene) + " --steps 3 --screenshot " + Quote(shot) +
                                     " --threads 1 --no-progress",
                                 dir),
                     "cannot write into", 1, "refused before the solver starts (which logs its device):\n");
}

using test::SpawnSphxr;

// Waits for the child until `deadline`; past it the child is killed and false returned.
bool WaitUntil(pid_t pid, std::chrono::steady_clock::time_point deadline, int* status) {
  while (waitpid(pid, status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, status, 0);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// Ctrl-C (or a SIGTERM from a batch system) during a long run stops it after the step in progress and
// loses nothing: whole CSV rows, one per step the summary counts, the state exported at that step, and
// the shell's exit code 128 + signal.
void InterruptRun(int signal, const char* name, bool repeat = false) {
  test::TempDir dir(std::string("interrupt_") + name);
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string csv = dir.File("stats.csv"), outPath = dir.File("out.txt"), errPath = dir.File("err.txt");
  const std::string out = (dir.path() / "out").string();
  const std::string state = dir.File("stopped.state");
  const pid_t pid = SpawnSphxr({"--headless", "--scene", scene, "--steps", "100000000", "--stats", csv, "--export-every",
                                "7", "--out", out, "--threads", "1", "--no-progress", "--save-state", state},
                               outPath, errPath);
  ASSERT_GE(pid, 0);
  // Signal once the run is under way (the CSV's buffer has reached the file).
  const auto start = std::chrono::steady_clock::now();
  test::WaitForFileSize(csv, 4096, std::chrono::milliseconds(50));
  ASSERT_EQ(kill(pid, signal), 0);
  int status = 0;
  bool reaped = false;
  if (repeat) {
    // Again every 0.1 ms until the process ends: while it stops, saves, prints and exits, any of them
    // taking the default action would lose the state and the summary.
    while (!(reaped = waitpid(pid, &status, WNOHANG) != 0) &&
           std::chrono::steady_clock::now() - start < std::chrono::seconds(120)) {
      kill(pid, signal);
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }
  ASSERT_TRUE(reaped || WaitUntil(pid, start + std::chrono::seconds(240), &status))
      << "the run did not stop after " << name;
  const std::string stdoutText = test::ReadFile(outPath), stderrText = test::ReadFile(errPath);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping:\n" << stderrText;
  EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << stderrText;
  EXPECT_NE(stdoutText.find(std::string("interrupted     by ") + name), std::string::npos) << stdoutText;
  EXPECT_NE(stderrText.find(" at step "), std::string::npos) << stderrText;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(stdoutText, m, std::regex(R"(steps +(\d+) )"))) << stdoutText;
  const long long steps = std::stoll(m[1]);
  ASSERT_GT(steps, 7);
  const std::vector<std::string> rows = Lines(test::ReadFile(csv));
  ASSERT_EQ(static_cast<long long>(rows.size()), steps + 1) << "a header and one row per step";
  const size_t fields = Split(rows[0], ',').size();
  for (size_t i = 1; i < rows.size(); ++i) ASSERT_EQ(Split(rows[i], ',').size(), fields) << "row " << i << ": " << rows[i];
  EXPECT_EQ(std::stoll(Split(rows.back(), ',')[0]), steps);
  char last[64];
  std::snprintf(last, sizeof(last), "particles_%06lld.ply", steps);
  const Ply ply = ReadPly((std::filesystem::path(out) / last).string());
  EXPECT_EQ(ply.vertices, static_cast<size_t>(kSmallSceneParticles)) << "the state at the interrupted step is exported";
  // and saved, at the time of the CSV's last row, to continue from.
  StateFile saved;
  const Status read = ReadStateFile(state, &saved);
  ASSERT_TRUE(read.ok()) << read.message();
  EXPECT_EQ(saved.fluidCount, kSmallSceneParticles);
  EXPECT_NEAR(saved.clock.time, std::stod(Split(rows.back(), ',')[1]), 1e-5);
}

// --settle relaxes the water before the run and then restarts the clock: the summary says so, the run's
// own steps are counted from 1 at t = dt, and the first export is the settled state, at rest.
TEST(HeadlessTest, SettleRunsBeforeTheRunAndRestartsTheClock) {
  test::TempDir dir("settle");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string csv = dir.File("stats.csv");
  const std::string out = dir.File("frames");
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --settle 0.05 --steps 10 --stats " + Quote(csv) +
                                 " --export-every 10 --out " + Quote(out) + " --threads 1 --no-progress",
                             dir);
  ASSERT_TRUE(r.Exited() && r.Code() == 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex(R"(settled +([0-9.]+) s of energy minimisation before t = 0 \((\d+) steps)")))
      << r.out;
  EXPECT_GE(std::stod(m[1]), 0.05);
  EXPECT_LT(std::stod(m[1]), 0.052) << "one step past the settle time at most";
  EXPECT_GT(std::stoll(m[2]), 10);
  EXPECT_NE(r.out.find("steps           10 "), std::string::npos) << "the settle's steps are not the run's:\n" << r.out;
  EXPECT_NE(r.err.find("settling: 0.05 simulated s"), std::string::npos) << r.err;
  const std::vector<std::string> rows = Lines(test::ReadFile(csv));
  ASSERT_EQ(rows.size(), 11u);
  const std::vector<std::string> first = Split(rows[1], ',');
  EXPECT_EQ(first[0], "1");
  EXPECT_DOUBLE_EQ(std::stod(first[1]), std::stod(first[2])) << "the clock restarts: t = dt after the first step";
  const Ply ply = ReadPly((std::filesystem::path(out) / "particles_000000.ply").string());
  EXPECT_EQ(ply.vertices, static_cast<size_t>(kSmallSceneParticles));
}

/// The regular files of `dir` by name (movie.mp4 aside: ffmpeg's container is not ours to compare).
std::map<std::string, std::string> FilesOf(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().filename() != "movie.mp4") files[e.path().filename().string()] = test::ReadFile(e.path().string());
  }
  return files;
}

// A run continued from its half-way file ends where the whole run ends, byte for byte, and goes on
// where the first half stopped: its steps, CSV rows, particle exports and frames are numbered and
// written as the whole run's, so both halves into one directory make the whole run's files.
TEST(HeadlessTest, ARunContinuedFromItsStateFileEndsWhereTheWholeRunEnds) {
  test::TempDir dir("state");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string half = dir.File("half.state"), continued = dir.File("continued.state"), whole = dir.File("whole.state");
  const std::string common = " --threads 1 --no-progress --scene " + Quote(scene);
  // Particles every 5 steps, surfaces every 10 and a 64 x 48 picture every 10 ms, each run into its own
  // directories. The first half stops at step 90, an export step: the continued run exports its start
  // again (the same bytes), as the whole run does at step 90.
  auto files = [&](const std::string& parts, const std::string& frames) {
    return " --export-every 5 --export-surface-every 10 --out " + Quote(dir.File(parts)) + " --frames " +
           Quote(dir.File(frames)) + " --fps 100 --image-size 64x48";
  };
  const Result first = RunBinary("--headless --steps 90 --save-state " + Quote(half) + " --stats " +
                                     Quote(dir.File("half.csv")) + files("parts", "frames") + common,
                                 dir);
  ASSERT_TRUE(first.Exited() && first.Code() == 0) << first.err;
  EXPECT_NE(first.out.find("state           saved to " + half), std::string::npos) << first.out;
  // The continued run's --stats is a copy of the first half's CSV: it appends the whole run's rows to it.
  std::filesystem::copy_file(dir.File("half.csv"), dir.File("joined.csv"));
  const std::string continuedRun = "--headless --time 0.04 --load-state " + Quote(half) + " --save-state " +
                                   Quote(continued) + " --stats " + Quote(dir.File("joined.csv")) +
                                   files("parts", "frames") + common;
  const Result second = RunBinary(continuedRun, dir);
  ASSERT_TRUE(second.Exited() && second.Code() == 0) << second.err;
  EXPECT_NE(second.err.find("started from " + half), std::string::npos) << second.err;
  EXPECT_NE(second.err.find("the rows continue the earlier run's (its steps up to 90 kept)"), std::string::npos) << second.err;
  EXPECT_EQ(second.err.find("was saved from scene"), std::string::npos) << "the same scene: " << second.err;
  EXPECT_NE(second.out.find("(from the state file)"), std::string::npos) << second.out;
  EXPECT_NE(second.out.find("of the whole run"), std::string::npos) << second.out;
  const Result through = RunBinary("--headless --time 0.04 --save-state " + Quote(whole) + " --stats " +
                                       Quote(dir.File("whole.csv")) + files("parts_whole", "frames_whole") + common,
                                   dir);
  ASSERT_TRUE(through.Exited() && through.Code() == 0) << through.err;

  const std::string a = test::ReadFile(continued), b = test::ReadFile(whole);
  ASSERT_GT(a.size(), static_cast<size_t>(kSmallSceneParticles) * 60) << "every field of every particle";
  EXPECT_TRUE(a == b) << "the continued run's state differs from the whole run's";

  // The first half's CSV with the continued run's rows is the whole run's: the step column counts on,
  // the clock goes on.
  const std::vector<std::string> halfRows = Lines(test::ReadFile(dir.File("half.csv"))),
                                 joinedRows = Lines(test::ReadFile(dir.File("joined.csv"))),
                                 wholeRows = Lines(test::ReadFile(dir.File("whole.csv")));
  ASSERT_EQ(halfRows.size(), 91u);  // header + 90 rows
  ASSERT_GT(joinedRows.size(), halfRows.size() + 1);
  EXPECT_EQ(WithoutCounts(joinedRows), WithoutCounts(wholeRows));
  EXPECT_TRUE(std::equal(halfRows.begin(), halfRows.end(), joinedRows.begin())) << "the first half's rows are kept";
  EXPECT_EQ(std::stoll(Split(joinedRows[91], ',')[0]), 91) << "the continued run numbers its steps on from the saved one";
  const long long lastStep = std::stoll(Split(wholeRows.back(), ',')[0]);
  EXPECT_NE(second.out.find(Format("exported        %lld files", 1 + (lastStep - 90) / 5)), std::string::npos)
      << "the start (step 90) and every fifth step after it:\n" << second.out;

  // Both halves' exports and frames in one directory are the whole run's, file for file and byte for byte
  // (before, the continued run wrote particles_000000 and frame_00000 again, over the first run's).
  const std::map<std::string, std::string> parts = FilesOf(dir.File("parts")), partsWhole = FilesOf(dir.File("parts_whole"));
  const std::map<std::string, std::string> frames = FilesOf(dir.File("frames")), framesWhole = FilesOf(dir.File("frames_whole"));
  EXPECT_GE(partsWhole.size(), 30u);  // particles and surfaces
  EXPECT_GE(framesWhole.size(), 5u);  // t = 0, 0.01, ..., 0.04
  std::vector<std::string> names, namesWhole;
  for (const auto& [name, bytes] : parts) names.push_back(name);
  for (const auto& [name, bytes] : partsWhole) namesWhole.push_back(name);
  for (const auto& [name, bytes] : frames) names.push_back(name);
  for (const auto& [name, bytes] : framesWhole) namesWhole.push_back(name);
  EXPECT_EQ(names, namesWhole);
  EXPECT_TRUE(parts == partsWhole) << "the exports of the two halves differ from the whole run's";
  EXPECT_TRUE(frames == framesWhole) << "the frames of the two halves differ from the whole run's";

  // A scene of another name with the same particles and spacing is used, and the name is said.
  std::string renamedText = kSmallScene;
  renamedText.replace(renamedText.find("headless_e2e"), 12, "renamed_tank");
  const std::string renamed = dir.Write("renamed.json", renamedText);
  const Result other = RunBinary("--headless --steps 2 --threads 1 --no-progress --load-state " + Quote(half) +
                                     " --scene " + Quote(renamed),
                                 dir);
  ASSERT_TRUE(other.Exited() && other.Code() == 0) << other.err;
  EXPECT_NE(other.err.find("was saved from scene 'headless_e2e', this scene is 'renamed_tank'"), std::string::npos)
      << other.err;

  // Refusals.
  ExpectOneLineError(RunBinary("--headless --time 0.04 --settle 1 --load-state " + Quote(half) + common, dir),
                     "--settle and --load-state");
  ExpectOneLineError(RunBinary("--headless --time 0.01 --load-state " + Quote(half) + common, dir), "at or past the end time");
  ExpectOneLineError(RunBinary("--headless --time 0.04 --load-state " + Quote(scene) + common, dir), "not an sphxr state file");
  ExpectOneLineError(RunBinary("--headless --time 0.04 --spacing 0.012 --load-state " + Quote(half) + common, dir),
                     "another --spacing");
  ExpectOneLineError(RunBinary("--headless --time 0.04 --set spacing=0.012 --load-state " + Quote(half) + common, dir),
                     "another --spacing");
  // Refused after --stats is checked: the CSV it names is left as it was.
  ExpectOneLineError(RunBinary("--headless --time 0.04 --stats " + Quote(dir.File("joined.csv")) + " --save-state " +
                                   Quote(dir.path().string()) + common,
                               dir),
                     "is a directory");
  EXPECT_EQ(Lines(test::ReadFile(dir.File("joined.csv"))), joinedRows) << "a refused run truncated its --stats file";
  // The second half run again into the joined CSV replaces its own earlier rows.
  const Result again = RunBinary(continuedRun, dir);
  ASSERT_TRUE(again.Exited() && again.Code() == 0) << again.err;
  EXPECT_NE(again.err.find(Format("its steps up to 90 kept, %zu rows after it replaced", wholeRows.size() - 91)),
            std::string::npos)
      << again.err;
  EXPECT_EQ(WithoutCounts(Lines(test::ReadFile(dir.File("joined.csv")))), WithoutCounts(wholeRows));
  ExpectOneLineError(RunBinary("--headless --time 0.04 --save-state /nonexistent/x.state" + common, dir),
                     "cannot write into");
}

// With a paddle: the state file holds the paddle's motion and the paddle system's own state (its
// commanded pose, mode, filtered force, frame clock), so a stirred run continued from its half-way file
// ends byte for byte where the whole run ends. (Before the paddles were saved, the paddle swept back
// from its start pose through the water, at 20 m/s.)
TEST(HeadlessTest, AStirredRunContinuedFromItsStateFileEndsWhereTheWholeRunEnds) {
  test::TempDir dir("state_paddle");
  const std::string scene = SPHXR_SCENES_DIR "/stir.json";
  const std::string half = dir.File("half.state"), continued = dir.File("continued.state"), whole = dir.File("whole.state");
  const std::string common = " --threads 1 --no-progress --spacing 0.015 --scene " + Quote(scene);
  const Result first = RunBinary("--headless --time 0.05 --save-state " + Quote(half) + common, dir);
  ASSERT_TRUE(first.Exited() && first.Code() == 0) << first.err;
  const Result second =
      RunBinary("--headless --time 0.1 --load-state " + Quote(half) + " --save-state " + Quote(continued) + common, dir);
  ASSERT_TRUE(second.Exited() && second.Code() == 0) << second.err;
  EXPECT_NE(second.out.find(", 0 teleport(s)"), std::string::npos) << second.out;
  const Result through = RunBinary("--headless --time 0.1 --save-state " + Quote(whole) + common, dir);
  ASSERT_TRUE(through.Exited() && through.Code() == 0) << through.err;
  EXPECT_NE(through.out.find("paddle          stirrer"), std::string::npos) << "the scene's paddle stirs:\n" << through.out;
  const std::string a = test::ReadFile(continued), b = test::ReadFile(whole);
  ASSERT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "the continued stirred run's state differs from the whole run's";
}

// An output that is one of the run's inputs, or another output, is refused before the run, and the file
// is left as it was (a typo in --stats wiped a state file). Saving over the state the run started from
// is allowed: a checkpoint carried forward.
TEST(HeadlessTest, OutputsThatAreInputsAreRefused) {
  test::TempDir dir("outputs_inputs");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string common = " --threads 1 --no-progress --steps 2 --scene " + Quote(scene);
  const std::string state = dir.File("a.state");
  ASSERT_EQ(RunBinary("--headless --save-state " + Quote(state) + common, dir).Code(), 0);
  const std::string sceneBytes = test::ReadFile(scene), stateBytes = test::ReadFile(state);
  ExpectOneLineError(RunBinary("--headless --stats " + Quote(scene) + common, dir), "is the scene");
  ExpectOneLineError(RunBinary("--headless --stats " + Quote(dir.path().string() + "/./scene.json") + common, dir),
                     "is the scene");
  ExpectOneLineError(RunBinary("--headless --load-state " + Quote(state) + " --stats " + Quote(state) + common, dir),
                     "is --load-state");
  const std::string csv = Quote(dir.File("x.csv"));
  ExpectOneLineError(RunBinary("--headless --stats " + csv + " --screenshot " + csv + common, dir), "is also --stats's file");
  // Spelled differently, neither existing yet.
  ExpectOneLineError(RunBinary("--headless --stats " + csv + " --save-state " + Quote(dir.path().string() + "/./x.csv") +
                                   common,
                               dir),
                     "is also --stats's file");
  EXPECT_EQ(test::ReadFile(scene), sceneBytes);
  EXPECT_EQ(test::ReadFile(state), stateBytes);
  // A paddle's trajectory (a copy of the stirring scene, which names its CSV relative to itself).
  std::filesystem::copy_file(SPHXR_SCENES_DIR "/stir.json", dir.File("stir.json"));
  std::filesystem::copy_file(SPHXR_SCENES_DIR "/stir_paddle.csv", dir.File("stir_paddle.csv"));
  const std::string trajectory = test::ReadFile(dir.File("stir_paddle.csv"));
  ExpectOneLineError(RunBinary("--headless --steps 1 --scene " + Quote(dir.File("stir.json")) + " --stats " +
                                   Quote(dir.File("stir_paddle.csv")),
                               dir),
                     "is the trajectory");
  EXPECT_EQ(test::ReadFile(dir.File("stir_paddle.csv")), trajectory);
  // A scene from a pipe is read once, by the run (the up-front check reads regular files only).
  const Result piped = RunBinary("--headless --steps 2 --threads 1 --no-progress --scene /dev/stdin < " + Quote(scene), dir);
  EXPECT_EQ(piped.Code(), 0) << piped.err;
  EXPECT_NE(piped.out.find("headless_e2e"), std::string::npos) << piped.out;
  // Carried forward in place: allowed, and the file is the longer run's.
  const Result forward = RunBinary("--headless --load-state " + Quote(state) + " --save-state " + Quote(state) + common, dir);
  ASSERT_EQ(forward.Code(), 0) << forward.err;
  StateFile after;
  ASSERT_TRUE(ReadStateFile(state, &after).ok());
  EXPECT_EQ(after.step, 4);
}

// A signal during the settling stops it too, with the summary and the exit code of an interrupted run.
TEST(HeadlessTest, InterruptDuringTheSettleStopsIt) {
  test::TempDir dir("settle_interrupt");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const std::string outPath = dir.File("out.txt"), errPath = dir.File("err.txt");
  const pid_t pid = SpawnSphxr(
      {"--headless", "--scene", scene, "--settle", "3600", "--steps", "5", "--threads", "1", "--no-progress",
       "--save-state", dir.File("partly.state")},
      outPath, errPath);
  ASSERT_GE(pid, 0);
  const auto start = std::chrono::steady_clock::now();
  while (test::ReadFile(errPath).find("settling:") == std::string::npos &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // a few hundred steps into it
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  int status = 0;
  ASSERT_TRUE(WaitUntil(pid, start + std::chrono::seconds(120), &status)) << "the settle did not stop after SIGTERM";
  const std::string stdoutText = test::ReadFile(outPath), stderrText = test::ReadFile(errPath);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping:\n" << stderrText;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM) << stderrText;
  EXPECT_NE(stdoutText.find("energy minimisation before t = 0, stopped early"), std::string::npos) << stdoutText;
  EXPECT_NE(stdoutText.find("interrupted     by SIGTERM"), std::string::npos) << stdoutText;
  EXPECT_NE(stdoutText.find("steps           0 "), std::string::npos) << "no step of the run was taken:\n" << stdoutText;
  // The water is saved (nothing is lost), and said to be unsettled: the file cannot say so itself, and a
  // run from it skips the scene's settle.
  EXPECT_NE(stderrText.find("settle stopped early at"), std::string::npos) << stderrText;
  EXPECT_EQ(stderrText.find("settled:"), std::string::npos) << stderrText;
  EXPECT_TRUE(std::filesystem::exists(dir.File("partly.state")));
  EXPECT_NE(stderrText.find("partly.state holds water whose settle was stopped at"), std::string::npos) << stderrText;
}

TEST(HeadlessTest, InterruptKeepsWholeRowsAndTheLastState) { InterruptRun(SIGINT, "SIGINT"); }
TEST(HeadlessTest, TerminateKeepsWholeRowsAndTheLastState) { InterruptRun(SIGTERM, "SIGTERM"); }
// A closed terminal or a dropped ssh session (long runs are started that way) is a stop too; before,
// the default action killed the run mid-row with no state and no summary.
// Sent again and again until the process has exited (a closing terminal's shell and the kernel may each
// send one, at any moment of the stop).
TEST(HeadlessTest, HangUpKeepsWholeRowsAndTheLastState) { InterruptRun(SIGHUP, "SIGHUP", true); }

TEST(HeadlessTest, OutWithoutAnExportIsNamed) {
  test::TempDir dir("outonly");
  const std::string scene = dir.Write("scene.json", kSmallScene);
  const Result r = RunBinary("--headless --scene " + Quote(scene) + " --steps 2 --out elsewhere --threads 1 --no-progress", dir);
  ASSERT_EQ(r.Code(), 0) << r.err;
  EXPECT_NE(r.err.find("--out elsewhere: nothing is exported without --export-every"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "elsewhere"));
}

TEST(HeadlessTest, HelpPrintsUsage) {
  test::TempDir dir("help");
  const Result r = RunBinary("--help", dir);
  ASSERT_EQ(r.Code(), 0) << r.err;
  EXPECT_EQ(r.out, UsageText());
}

}  // namespace
}  // namespace sphxr::app
