#pragma once
// Shared helpers for the unit tests: small scenes built in code, solver creation with a readable
// failure, log capture, temporary directories, and per-particle lookups by id.
#include <system_error>
#include <thread>
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

#include <sstream>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "sphxr/common/log.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver.h"

namespace sphxr::test {

using sim::Aabb;
using sim::FluidBlock;
using sim::HostFluid;
using sim::SceneSetup;
using sim::Vec3;
using sim::Vec4;

/// A scene file's text: a water block of 12 x 10 x 6 = 720 particles in a 0.2 x 0.15 x 0.1 m tank (a
/// surface of some hundreds of triangles), for the app and render tests.
constexpr const char* kSmallTankScene = R"({
  "name": "small",
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.15, 0.1] },
  "fluid": [ { "min": [0.04, 0.0, 0.02], "max": [0.16, 0.10, 0.08] } ],
  "run": { "steps": 2 }
})";

inline Aabb Box(Vec3 min, Vec3 max) { return Aabb{min, max}; }

inline FluidBlock Block(Vec3 min, Vec3 max, Vec3 velocity = {}) { return FluidBlock{Aabb{min, max}, velocity}; }

/// A tank from `min` to `max` with rest spacing `spacing`, no fluid yet, open top, default physics.
inline SceneSetup TankScene(Vec3 min, Vec3 max, float spacing) {
  SceneSetup s;
  s.params.spacing = spacing;
  s.tank = Aabb{min, max};
  s.openTop = true;
  return s;
}

/// A small dam break: a column 0.1 x 0.15 x 0.06 m against the back wall of a 0.3 x 0.2 x 0.06 m tank
/// (spacing 0.01 m: 10 x 15 x 6 = 900 fluid particles).
inline SceneSetup SmallDamBreak(float spacing = 0.01f) {
  SceneSetup s = TankScene({0, 0, 0}, {0.3f, 0.2f, 0.06f}, spacing);
  s.params.maxDt = 1e-3f;
  s.fluid.push_back(Block({0, 0, 0}, {0.1f, 0.15f, 0.06f}));
  return s;
}

/// tank_rest under PBF: a 0.2 m column filling a closed 0.2 x 0.3 x 0.1 m box (20 x 20 x 10 particles at
/// 1 cm) at rest.
inline SceneSetup PbfStillWater(float spacing = 0.01f) {
  SceneSetup s = TankScene({0, 0, 0}, {0.2f, 0.3f, 0.1f}, spacing);
  s.method = sim::SolverMethod::kPbf;
  s.openTop = false;
  s.fluid.push_back(Block({0, 0, 0}, {0.2f, 0.2f, 0.1f}));
  return s;
}

/// The backend named by the argument --sphxr-device=NAME, else by SPHXR_TEST_DEVICE; empty: none named.
/// ctest passes the argument (tests/CMakeLists.txt): gtest_discover_tests (CMake 3.25) splits a list in
/// PROPERTIES, so a discovered test's ENVIRONMENT cannot hold a second variable beside OMP_WAIT_POLICY.
/// gtest_main leaves arguments it does not know alone; the test reads its own command line.
inline std::string TestDeviceName() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string flag = "--sphxr-device=";
  for (std::string arg; std::getline(in, arg, '\0');) {
    if (arg.rfind(flag, 0) == 0) return arg.substr(flag.size());
  }
  const char* env = std::getenv("SPHXR_TEST_DEVICE");
  return env ? env : "";
}

/// The backend the suites run on: `cpu`, or the one TestDeviceName names (cpu, cpu-reference, cuda).
/// ctest runs the sim and interaction suites once more on cpu-reference, so that the CUDA backend's
/// orchestration passes every behaviour test here (docs/dev/backends.md). An unknown name fails loudly
/// rather than testing the wrong backend.
inline sim::Device TestDevice() {
  const std::string name = TestDeviceName();
  sim::Device d = sim::Device::kCpu;
  if (!name.empty() && (!sim::ParseDevice(name, &d) || d == sim::Device::kAuto)) {
    std::fprintf(stderr, "test device '%s': must be cpu, cpu-reference or cuda\n", name.c_str());
    std::abort();
  }
  return d;
}

/// Every backend on this machine: cpu, cpu-reference, and cuda when a device answers (value-parameterised
/// suites over backends).
inline std::vector<sim::Device> AvailableDevices() {
  std::vector<sim::Device> d = {sim::Device::kCpu, sim::Device::kCpuReference};
  if (sim::CudaDeviceCount() > 0) d.push_back(sim::Device::kCuda);
  return d;
}

/// A test name for a backend ("cpu_reference": gtest names take no '-').
inline std::string DeviceTestName(sim::Device device) {
  std::string s = sim::DeviceName(device);
  for (char& c : s) c = c == '-' ? '_' : c;
  return s;
}

/// The configuration the tests use unless they test threading or devices: the test backend (TestDevice)
/// on one thread. (ctest runs two test processes at once on a 2-core machine; two OpenMP teams of 2
/// spinning threads each slow every step down by two orders of magnitude.)
inline sim::SolverConfig TestConfig() {
  sim::SolverConfig c;
  c.device = TestDevice();
  c.threads = 1;
  return c;
}

/// SolverConfig{} (the default device and every core) on the test backend, for the suites that run on
/// all cores.
inline sim::SolverConfig AllCoresConfig() {
  sim::SolverConfig c;
  if (!TestDeviceName().empty()) c.device = TestDevice();
  return c;
}

/// Creates a solver or fails the current test with the status message.
inline std::unique_ptr<sim::Solver> CreateOrFail(const SceneSetup& scene, sim::SolverConfig config = TestConfig()) {
  std::unique_ptr<sim::Solver> solver;
  const Status s = sim::Solver::Create(scene, config, &solver);
  EXPECT_TRUE(s.ok()) << "Solver::Create failed: " << s.message();
  return solver;
}

inline sim::HostFluid DownloadFluid(const sim::Solver& solver) {
  sim::HostFluid h;
  solver.Download(&h);
  return h;
}

inline bool Finite(Vec4 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// Empty string when every position, velocity, acceleration, density and pressure is finite; otherwise
/// the first offender (for a failure message).
inline std::string FirstNonFinite(const HostFluid& f) {
  for (size_t i = 0; i < f.size(); ++i) {
    const char* bad = nullptr;
    if (!Finite(f.position[i])) bad = "position";
    else if (!Finite(f.velocity[i])) bad = "velocity";
    else if (!Finite(f.acceleration[i])) bad = "acceleration";
    else if (!std::isfinite(f.density[i])) bad = "density";
    else if (!std::isfinite(f.pressure[i])) bad = "pressure";
    if (bad) {
      return Format("non-finite %s of particle id %u (index %zu): position [%g %g %g] velocity [%g %g %g]", bad, f.id[i],
                    i, f.position[i].x, f.position[i].y, f.position[i].z, f.velocity[i].x, f.velocity[i].y,
                    f.velocity[i].z);
    }
  }
  return {};
}

/// index of each id in `f`
inline std::unordered_map<uint32_t, size_t> IndexById(const HostFluid& f) {
  std::unordered_map<uint32_t, size_t> m;
  for (size_t i = 0; i < f.size(); ++i) m[f.id[i]] = i;
  return m;
}

/// Steps `n` times; fails the test (and returns false) at the first error status.
inline bool StepN(sim::Solver& solver, int n) {
  for (int k = 0; k < n; ++k) {
    const Status s = solver.Step();
    if (!s.ok()) {
      ADD_FAILURE() << "Step " << solver.GetTotals().steps + 1 << " failed: " << s.message();
      return false;
    }
  }
  return true;
}

/// Collects log messages while alive (the sink is process-global; restored on destruction).
class LogCapture {
 public:
  LogCapture() {
    m_previousLevel = GetLogLevel();
    SetLogLevel(LogLevel::kDebug);
    SetLogSink([this](LogLevel level, const std::string& text) {
      std::lock_guard lock(m_mutex);
      m_messages.push_back({level, text});
    });
  }
  ~LogCapture() {
    SetLogSink(nullptr);
    SetLogLevel(m_previousLevel);
  }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;

  struct Message {
    LogLevel level;
    std::string text;
  };
  std::vector<Message> Messages() const {
    std::lock_guard lock(m_mutex);
    return m_messages;
  }
  int Count(const std::string& needle, LogLevel level = LogLevel::kDebug) const {
    std::lock_guard lock(m_mutex);
    int n = 0;
    for (const Message& m : m_messages) n += (m.level >= level && m.text.find(needle) != std::string::npos) ? 1 : 0;
    return n;
  }
  std::string All() const {
    std::lock_guard lock(m_mutex);
    std::string s;
    for (const Message& m : m_messages) s += "  [" + std::to_string(static_cast<int>(m.level)) + "] " + m.text + "\n";
    return s;
  }

 private:
  mutable std::mutex m_mutex;
  std::vector<Message> m_messages;
  LogLevel m_previousLevel = LogLevel::kInfo;
};

/// A fresh directory under the system temp dir, removed on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    const auto base = std::filesystem::temp_directory_path();
    std::random_device rd;
    for (int attempt = 0; attempt < 100; ++attempt) {
      const auto p = base / ("sphxr_test_" + tag + "_" + std::to_string(rd()));
      std::error_code ec;
      if (std::filesystem::create_directory(p, ec)) {
        m_path = p;
        return;
      }
    }
    ADD_FAILURE() << "cannot create a temporary directory under " << base;
  }
  ~TempDir() {
    std::error_code ec;
    if (!m_path.empty()) std::filesystem::remove_all(m_path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return m_path; }
  std::string File(const std::string& name) const { return (m_path / name).string(); }
  std::string Write(const std::string& name, const std::string& content) const {
    const std::string p = File(name);
    std::ofstream out(p, std::ios::binary);
    out << content;
    return p;
  }

 private:
  std::filesystem::path m_path;
};

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Seconds taken by f().
inline double Seconds(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The lines of `text`, without their newlines.
inline std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Waits until the file at `path` holds at least `bytes` (a run's CSV buffer has reached it), polling every
/// `poll`, for at most `limit`. Returns whether it did.
inline bool WaitForFileSize(const std::string& path, uintmax_t bytes, std::chrono::milliseconds poll,
                            std::chrono::seconds limit = std::chrono::seconds(120)) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && size >= bytes) return true;
    if (std::chrono::steady_clock::now() - start >= limit) return false;
    std::this_thread::sleep_for(poll);
  }
}

#ifdef SPHXR_BINARY
/// Starts the real binary with `args` in a child whose stdout and stderr go to the two files. SIGINT,
/// SIGTERM and SIGHUP start at their defaults, as from a terminal: a signal this test's own parent
/// ignores (a background job, nohup, a CI runner) must not stay ignored. `inChild` runs in the child
/// just before the program starts (a resource limit, another user; it calls _exit(126) when it fails).
inline pid_t SpawnSphxr(const std::vector<std::string>& args, const std::string& outPath, const std::string& errPath,
                        const std::function<void()>& inChild = {}) {
  std::vector<char*> argv{const_cast<char*>(SPHXR_BINARY)};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int o = open(outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = open(errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(o, 1);
    dup2(e, 2);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    ::signal(SIGHUP, SIG_DFL);
    if (inChild) inChild();
    execv(SPHXR_BINARY, argv.data());
    _exit(127);
  }
  return pid;
}
#endif

/// Two surface fields sampled on the same lattice lines at one cell size, one lattice within the other
/// (the CPU backend's covers the particles' bounding box, cpu-reference's and CUDA's the clamp box):
/// the largest difference where both sample, and the largest value the larger one has elsewhere.
struct SurfaceFieldDiff {
  bool nested = false;  // same cell size, one lattice within the other on shared lines
  float worst = 0.0f, outside = 0.0f;
};
inline SurfaceFieldDiff CompareSurfaceFields(const sim::SurfaceGrid& ga, const std::vector<float>& fa,
                                             const sim::SurfaceGrid& gb, const std::vector<float>& fb) {
  const bool aBig = ga.Samples() >= gb.Samples();
  const sim::SurfaceGrid& big = aBig ? ga : gb;
  const sim::SurfaceGrid& small = aBig ? gb : ga;
  const std::vector<float>& bigField = aBig ? fa : fb;
  const std::vector<float>& smallField = aBig ? fb : fa;
  SurfaceFieldDiff d;
  if (big.cellSize != small.cellSize || static_cast<int64_t>(bigField.size()) != big.Samples() ||
      static_cast<int64_t>(smallField.size()) != small.Samples()) {
    return d;
  }
  const float o[3] = {small.origin.x - big.origin.x, small.origin.y - big.origin.y, small.origin.z - big.origin.z};
  const int n[3] = {small.nx, small.ny, small.nz}, nBig[3] = {big.nx, big.ny, big.nz};
  int off[3];
  for (int a = 0; a < 3; ++a) {
    off[a] = static_cast<int>(std::lround(o[a] / big.cellSize));
    if (off[a] < 0 || off[a] + n[a] > nBig[a]) return d;
  }
  d.nested = true;
  for (int k = 0; k < big.nz; ++k)
    for (int j = 0; j < big.ny; ++j)
      for (int i = 0; i < big.nx; ++i) {
        const float v = bigField[i + static_cast<size_t>(big.nx) * (j + static_cast<size_t>(big.ny) * k)];
        const int si = i - off[0], sj = j - off[1], sk = k - off[2];
        if (si < 0 || sj < 0 || sk < 0 || si >= small.nx || sj >= small.ny || sk >= small.nz) {
          d.outside = std::max(d.outside, std::fabs(v));
          continue;
        }
        const float w = smallField[si + static_cast<size_t>(small.nx) * (sj + static_cast<size_t>(small.ny) * sk)];
        d.worst = std::max(d.worst, std::fabs(v - w));
      }
  return d;
}

}  // namespace sphxr::test
