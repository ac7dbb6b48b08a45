// The headless runner's probes and timed exports end to end (the sphxr binary): `--probes FILE.csv`
// gives rows exactly probes.every apart whatever the adaptive step, `--export-interval S` and
// `--export-surface-interval S` export at the first step at or after each multiple of S, and every
// export names its step and time (PLY comment, VTK field data, OBJ comment).
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "support.h"

namespace sphxr::app {
namespace {

// A small dam break (0.1 x 0.15 m column, 900 particles): its adaptive step shrinks as the water speeds up.
constexpr const char* kScene = R"({
  "name": "probe_e2e",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.3, 0.2, 0.06] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.15, 0.06] } ],
  "probes": { "every": 0.001,
    "pressure": [ { "name": "far", "at": [0.3, 0.02, 0.03], "normal": [1, 0, 0] },
                  { "name": "back", "at": [0.0, 0.02, 0.03], "normal": [-1, 0, 0] } ],
    "level": [ { "name": "column", "x": 0.05, "z": 0.03 } ] }
})";

struct SphxrRun {
  int code = -1;
  std::string out, err;
};

SphxrRun Sphxr(const test::TempDir& dir, const std::vector<std::string>& args) {
  SphxrRun r;
  const std::string out = dir.File("stdout.txt"), err = dir.File("stderr.txt");
  const pid_t pid = test::SpawnSphxr(args, out, err);
  int status = 0;
  waitpid(pid, &status, 0);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = test::ReadFile(out);
  r.err = test::ReadFile(err);
  return r;
}

std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

TEST(HeadlessTest, ProbeRowsOneMillisecondApartWhateverTheStep) {
  test::TempDir dir("probes");
  const std::string scene = dir.Write("scene.json", kScene);
  const std::string csv = dir.File("probes.csv"), stats = dir.File("stats.csv");
  const SphxrRun r = Sphxr(dir, {"--headless", "--scene", scene, "--time", "0.04", "--probes", csv, "--stats", stats,
                            "--threads", "1", "--no-progress"});
  ASSERT_EQ(r.code, 0) << r.err;
  // The steps differ (the adaptive step), and none is a divisor of 1 ms that the rows could ride on.
  std::map<std::string, int> dts;
  const std::vector<std::string> statRows = test::Lines(test::ReadFile(stats));
  for (size_t i = 1; i < statRows.size(); ++i) ++dts[Cells(statRows[i])[2]];
  EXPECT_GT(dts.size(), 3u) << "expected the adaptive step to change";

  const std::vector<std::string> lines = test::Lines(test::ReadFile(csv));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "time,step,far_p,back_p,column_level");
  // Rows at 0, 1, ..., 39 ms: the last reading is of the last step's start, before 40 ms.
  ASSERT_GE(lines.size(), 1u + 39u);
  for (size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> cells = Cells(lines[k]);
    ASSERT_EQ(cells.size(), 5u) << lines[k];
    EXPECT_NEAR(std::stod(cells[0]), 0.001 * static_cast<double>(k - 1), 1e-12) << lines[k];
    EXPECT_FALSE(cells[3].empty()) << "the back wall under the column is wet: " << lines[k];
    EXPECT_FALSE(cells[4].empty()) << "the gauge in the column sees water: " << lines[k];
  }
  // The far wall is dry at the start: the water has not arrived.
  EXPECT_TRUE(Cells(lines[1])[2].empty()) << lines[1];
}

TEST(HeadlessTest, ProbesWithoutASectionAreRefused) {
  test::TempDir dir("probes_none");
  const std::string scene = dir.Write("scene.json", test::kSmallTankScene);
  const SphxrRun r = Sphxr(dir, {"--headless", "--scene", scene, "--steps", "2", "--probes", dir.File("p.csv"), "--no-progress"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("--probes"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no \"probes\" section"), std::string::npos) << r.err;
}

/// The step and time a PLY header's comment names (-1 when it has none).
std::pair<int64_t, double> PlyStamp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::regex stamp(R"(comment step (\d+) time ([0-9.eE+-]+))");
  for (std::string line; std::getline(in, line) && line != "end_header";) {
    std::smatch m;
    if (std::regex_match(line, m, stamp)) return {std::stoll(m[1]), std::stod(m[2])};
  }
  return {-1, 0.0};
}

/// The TIME (big-endian double) and CYCLE (big-endian int) of a legacy VTK file's field data.
std::pair<int64_t, double> VtkStamp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::pair<int64_t, double> out{-1, 0.0};
  const size_t field = bytes.find("FIELD FieldData 2\nTIME 1 1 double\n");
  if (field == std::string::npos) return out;
  size_t at = field + std::strlen("FIELD FieldData 2\nTIME 1 1 double\n");
  uint64_t t;
  std::memcpy(&t, bytes.data() + at, 8);
  t = __builtin_bswap64(t);
  std::memcpy(&out.second, &t, 8);
  at += 8;
  const std::string cycle = "\nCYCLE 1 1 int\n";
  if (bytes.compare(at, cycle.size(), cycle) != 0) return out;
  uint32_t c;
  std::memcpy(&c, bytes.data() + at + cycle.size(), 4);
  out.first = static_cast<int32_t>(__builtin_bswap32(c));
  return out;
}

// --export-interval: a file at the first step at or after each multiple of the interval, named by its
// step, whose stamp gives that step and its time (checked against the stats CSV's row of that step).
TEST(HeadlessTest, ExportIntervalStampsStepAndTime) {
  for (const std::string format : {"ply", "vtk"}) {
    SCOPED_TRACE(format);
    test::TempDir dir("export_interval");
    const std::string scene = dir.Write("scene.json", kScene);
    const std::string out = dir.File("out"), stats = dir.File("stats.csv");
    const SphxrRun r = Sphxr(dir, {"--headless", "--scene", scene, "--time", "0.03", "--export-interval", "0.01",
                              "--export-format", format, "--export-surface-interval", "0.015", "--surface-format", "obj",
                              "--out", out, "--stats", stats, "--threads", "1", "--no-progress"});
    ASSERT_EQ(r.code, 0) << r.err;
    std::map<int64_t, double> timeOfStep{{0, 0.0}};
    const std::vector<std::string> rows = test::Lines(test::ReadFile(stats));
    for (size_t i = 1; i < rows.size(); ++i) {
      const std::vector<std::string> c = Cells(rows[i]);
      timeOfStep[std::stoll(c[0])] = std::stod(c[1]);
    }
    std::vector<std::pair<int64_t, double>> particles, surfaces;
    for (const auto& entry : std::filesystem::directory_iterator(out)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("particles_", 0) == 0) {
        particles.push_back(format == "ply" ? PlyStamp(entry.path().string()) : VtkStamp(entry.path().string()));
        EXPECT_EQ(std::stoll(name.substr(10, 6)), particles.back().first) << name << " names another step than its stamp";
      } else if (name.rfind("surface_", 0) == 0) {
        std::ifstream in(entry.path());
        std::string first, second;
        std::getline(in, first);
        std::getline(in, second);
        std::smatch m;
        ASSERT_TRUE(std::regex_match(second, m, std::regex(R"(# step (\d+) time ([0-9.eE+-]+))"))) << second;
        surfaces.push_back({std::stoll(m[1]), std::stod(m[2])});
      }
    }
    std::sort(particles.begin(), particles.end());
    std::sort(surfaces.begin(), surfaces.end());
    // Particles at 0, 10, 20, 30 ms (the run ends at the first step at or after 30 ms); the surface at
    // 0, 15, 30 ms.
    auto check = [&](const std::vector<std::pair<int64_t, double>>& files, double interval, size_t count) {
      ASSERT_EQ(files.size(), count);
      for (size_t k = 0; k < files.size(); ++k) {
        const auto [step, time] = files[k];
        ASSERT_TRUE(timeOfStep.count(step)) << "step " << step;
        EXPECT_NEAR(time, timeOfStep[step], 1e-6 * (1.0 + time)) << "the stamp's time is the step's";
        const double due = interval * static_cast<double>(k);
        EXPECT_GE(time, due - 1e-12) << "file " << k << " before its time";
        if (step > 0) {
          EXPECT_LT(timeOfStep[step - 1], due) << "file " << k << ": the step before had reached it";
        }
      }
    };
    check(particles, 0.01, 4);
    check(surfaces, 0.015, 3);
  }
}

// A fixed structure (a scripted paddle whose trajectory is one pose, held) in still water: its force
// probe reads Archimedes' buoyancy, rho0 g times the submerged volume. Where the water's surface against
// the structure lies is resolution-dependent: between the solid's faces and half a spacing out (the
// fluid keeps half a spacing from its shell), so the buoyancy lies between that of the solid and of the
// solid grown by half a spacing, at the water level the gauge reads. Averaged over the last 0.2 s of 0.6 s
// (the start's sloshing has calmed).
TEST(HeadlessTest, AHeldStructureFeelsArchimedesBuoyancy) {
  test::TempDir dir("buoyancy");
  dir.Write("hold.csv", "time,px,py,pz\n0,0.15,0.10,0.10\n");
  const std::string scene = dir.Write("scene.json", R"({
    "name": "held_post",
    "solver": { "spacing": 0.01, "stiffness": 20000.0, "viscosity": 0.05 },
    "tank": { "min": [0, 0, 0], "max": [0.3, 0.25, 0.2], "wall_pressure": "wall_density" },
    "fluid": [ { "min": [0, 0, 0], "max": [0.3, 0.12, 0.2], "hydrostatic": true } ],
    "paddles": { "frame_rate": 90, "list": [ { "name": "post", "hand": "script", "trajectory": "hold.csv",
        "shapes": [ { "box": { "center": [0, 0, 0], "half_extents": [0.03, 0.05, 0.03] } } ] } ] },
    "probes": { "every": 0.01, "force": [ { "name": "F", "body": "post" } ],
                "level": [ { "name": "L", "x": 0.04, "z": 0.04 } ] }
  })");
  const std::string csv = dir.File("probes.csv");
  const SphxrRun r = Sphxr(dir, {"--headless", "--scene", scene, "--time", "0.6", "--probes", csv, "--threads", "1",
                                 "--no-progress"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> lines = test::Lines(test::ReadFile(csv));
  ASSERT_FALSE(lines.empty());
  ASSERT_EQ(lines[0], "time,step,L_level,F_fx,F_fy,F_fz,F_tx,F_ty,F_tz");
  double fy = 0.0, level = 0.0;
  int n = 0;
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> c = Cells(lines[i]);
    ASSERT_EQ(c.size(), 9u) << lines[i];
    if (std::stod(c[0]) < 0.4 - 1e-9) continue;
    level += std::stod(c[2]);
    fy += std::stod(c[4]);
    ++n;
  }
  ASSERT_GE(n, 19);
  fy /= n;
  level /= n;
  const double rho0g = 1000.0 * 9.81, dx = 0.01, bottom = 0.05, half = 0.03;
  ASSERT_GT(level, bottom + 0.05) << "the post stands in the water";
  const double solid = rho0g * (2 * half) * (2 * half) * (level - bottom);
  const double grown = rho0g * (2 * half + dx) * (2 * half + dx) * (level - bottom + 0.5 * dx);
  std::printf("buoyancy %.3f N: solid %.3f N, grown by half a spacing %.3f N (level %.4f m)\n", fy, solid, grown, level);
  EXPECT_GE(fy, solid);
  EXPECT_LE(fy, grown);
}

// A run continued from its state file continues its probe file: the rows of the whole run, at the same
// times, with the same readings (to float rounding: the reading of the final state at the join is taken
// after a re-grid, its sums in another order), and an earlier continuation's rows past the state replaced.
TEST(HeadlessTest, AContinuedRunContinuesItsProbeFile) {
  test::TempDir dir("probes_continue");
  const std::string scene = dir.Write("scene.json", kScene);
  const std::string whole = dir.File("whole.csv"), parts = dir.File("parts.csv"), state = dir.File("mid.state");
  const std::vector<std::string> common = {"--headless", "--scene", scene, "--threads", "1", "--no-progress"};
  auto run = [&](std::vector<std::string> more) {
    std::vector<std::string> args = common;
    args.insert(args.end(), more.begin(), more.end());
    return Sphxr(dir, args);
  };
  SphxrRun r = run({"--time", "0.04", "--probes", whole});
  ASSERT_EQ(r.code, 0) << r.err;
  // The first half, then a second half run twice (the second time its own rows are replaced).
  r = run({"--time", "0.0205", "--probes", parts, "--save-state", state});
  ASSERT_EQ(r.code, 0) << r.err;
  for (int k = 0; k < 2; ++k) {
    r = run({"--time", "0.04", "--load-state", state, "--probes", parts});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("the rows continue the earlier run's"), std::string::npos) << r.err;
  }
  const std::vector<std::string> a = test::Lines(test::ReadFile(whole)), b = test::Lines(test::ReadFile(parts));
  ASSERT_EQ(b.size(), a.size()) << "the same rows";
  ASSERT_GT(a.size(), 40u);
  EXPECT_EQ(b[0], a[0]);
  for (size_t i = 1; i < a.size(); ++i) {
    const std::vector<std::string> x = Cells(a[i]), y = Cells(b[i]);
    ASSERT_EQ(y.size(), x.size()) << b[i];
    EXPECT_EQ(y[0], x[0]) << "row " << i << ": the same time";
    for (size_t c = 2; c < x.size(); ++c) {
      ASSERT_EQ(x[c].empty(), y[c].empty()) << "row " << i << " column " << c << ": " << a[i] << " / " << b[i];
      if (x[c].empty()) continue;
      const double u = std::stod(x[c]), v = std::stod(y[c]);
      EXPECT_NEAR(v, u, 1e-4 * (std::fabs(u) + 1.0)) << "row " << i << " column " << c;
    }
  }
}

}  // namespace
}  // namespace sphxr::app
