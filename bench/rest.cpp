// sphxr_bench_rest: how still water at rest really is (docs/design/settle.md).
//
// Runs a scene (default scenes/tank_rest.json) in windows of fixed simulated length and prints, per
// window, the particle drift (median, 90th percentile, maximum, in spacings) and the mean and maximum
// speed; at the end the layer-averaged pressure against rho0 g depth, each particle compared at its own
// depth below the free surface (the top particle's centre plus half a spacing). It reports; it never
// asserts. A drift that does not fall from window to window means something keeps doing work on the
// water; the hydrostatic test (tests/validation/hydrostatic_test.cpp) looks at one window only.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/sim/measure.h"
#include "sphxr/sim/solver.h"

namespace {

using sphxr::sim::HostFluid;
using sphxr::sim::Vec4;

void Usage() {
  std::fprintf(stderr,
               "usage: sphxr_bench_rest [--scene FILE] [--windows N] [--window S] [--threads N] [--wall-pressure W] [--detail]\n"
               "                        [--energy] [--damp FROM UNTIL RATE] [--settle S]\n"
               "  --scene FILE  scene (default %s/tank_rest.json)\n"
               "  --windows N   number of windows (default 6)\n"
               "  --window S    simulated seconds per window (default 0.5)\n"
               "  --threads N   CPU backend threads (default 0 = all cores)\n"
               "  --wall-pressure W  mirrored | wall_density: override the scene's tank.wall_pressure\n"
               "  --detail      the 12 largest drifts of the last window; per layer the mean height and the\n"
               "                pressure and density of the particles 2.5 spacings or more from the side walls\n"
               "  --energy      after each window the total energy (sim/measure.h SphEnergy: kinetic, gravity,\n"
               "                the fluid's and the walls' internal energy)\n"
               "  --damp FROM UNTIL RATE  multiply every velocity by exp(-RATE dt) after each step between FROM and\n"
               "                UNTIL seconds (a quench: does the motion come back once it is off?)\n"
               "  --settle S    first Solver::Settle for S simulated seconds (FIRE on the solver's steps, Bitzek et\n"
               "                al. 2006; sphxr --settle); the windows then start at its rest state, at t = 0\n",
               SPHXR_SCENES_DIR);
}

bool ParsePositive(const char* text, double* out) {
  double v = 0.0;
  if (!sphxr::bench::ParseNumber(text, &v) || !(v > 0.0)) return false;
  *out = v;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath = std::string(SPHXR_SCENES_DIR) + "/tank_rest.json";
  double windows = 6, window = 0.5, threads = 0;
  double dampFrom = -1.0, dampUntil = -1.0, dampRate = 0.0;  // --damp: no damping unless asked
  double settle = 0.0;                                         // --settle: none unless asked
  bool detail = false, energy = false;
  double energyStart = 0.0;
  std::string wallPressure;
  for (int a = 1; a < argc; ++a) {
    const bool hasValue = a + 1 < argc;
    if (!std::strcmp(argv[a], "--scene") && hasValue) {
      scenePath = argv[++a];
    } else if (!std::strcmp(argv[a], "--windows") && hasValue) {
      if (!ParsePositive(argv[++a], &windows)) return std::fprintf(stderr, "sphxr_bench_rest: --windows wants a positive number\n"), 2;
    } else if (!std::strcmp(argv[a], "--window") && hasValue) {
      if (!ParsePositive(argv[++a], &window)) return std::fprintf(stderr, "sphxr_bench_rest: --window wants positive seconds\n"), 2;
    } else if (!std::strcmp(argv[a], "--damp") && a + 3 < argc) {
      if (!sphxr::bench::ParseNumber(argv[a + 1], &dampFrom) || !sphxr::bench::ParseNumber(argv[a + 2], &dampUntil) ||
          !(dampFrom >= 0.0) || !(dampUntil > dampFrom) || !ParsePositive(argv[a + 3], &dampRate))
        return std::fprintf(stderr, "sphxr_bench_rest: --damp wants FROM UNTIL RATE: 0 <= FROM < UNTIL seconds, RATE > 0 per second\n"), 2;
      a += 3;
    } else if (!std::strcmp(argv[a], "--settle") && hasValue) {
      if (!ParsePositive(argv[++a], &settle)) return std::fprintf(stderr, "sphxr_bench_rest: --settle wants positive seconds\n"), 2;
    } else if (!std::strcmp(argv[a], "--energy")) {
      energy = true;
    } else if (!std::strcmp(argv[a], "--detail")) {
      detail = true;
    } else if (!std::strcmp(argv[a], "--wall-pressure") && hasValue) {
      wallPressure = argv[++a];
      if (wallPressure != "mirrored" && wallPressure != "wall_density")
        return std::fprintf(stderr, "sphxr_bench_rest: --wall-pressure wants mirrored or wall_density\n"), 2;
    } else if (!std::strcmp(argv[a], "--threads") && hasValue) {
      if (!ParsePositive(argv[++a], &threads)) return std::fprintf(stderr, "sphxr_bench_rest: --threads wants a positive count\n"), 2;
    } else if (!std::strcmp(argv[a], "--help") || !std::strcmp(argv[a], "-h")) {
      Usage();
      return 0;
    } else {
      std::fprintf(stderr, "sphxr_bench_rest: %s: unknown option, or its values are missing\n", argv[a]);
      Usage();
      return 2;
    }
  }
  sphxr::app::SceneFile scene;
  if (sphxr::Status s = sphxr::app::LoadScene(scenePath, &scene); !s) {
    std::fprintf(stderr, "sphxr_bench_rest: %s\n", s.message().c_str());
    return 1;
  }
  if (wallPressure == "mirrored") scene.setup.wallPressure = sphxr::sim::SceneSetup::WallPressure::kMirrored;
  if (wallPressure == "wall_density") scene.setup.wallPressure = sphxr::sim::SceneSetup::WallPressure::kWallDensity;
  sphxr::sim::SolverConfig config;
  config.threads = static_cast<int>(threads);
  std::unique_ptr<sphxr::sim::Solver> solver;
  if (sphxr::Status s = sphxr::sim::Solver::Create(scene.setup, config, &solver); !s) {
    std::fprintf(stderr, "sphxr_bench_rest: %s\n", s.message().c_str());
    return 1;
  }
  const float dx = scene.setup.params.spacing;
  std::printf("scene %s: %lld fluid particles, spacing %g m; %d windows of %g s\n", scenePath.c_str(),
              static_cast<long long>(solver->FluidCount()), dx, static_cast<int>(windows), window);
  std::printf("| window (s) | drift median | q90 | max (spacings) | mean speed (mm/s) | max speed (mm/s) | clamped |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  HostFluid previous, damped;
  if (settle > 0.0) {
    sphxr::sim::SettleReport report;
    if (sphxr::Status s = solver->Settle(settle, &report); !s) {
      std::fprintf(stderr, "sphxr_bench_rest: %s\n", s.message().c_str());
      return 1;
    }
    std::printf("settled: %.4g s, %lld steps, %.1f s wall; largest |a| at the end %.3g m/s^2; windows from t = 0\n",
                report.time, static_cast<long long>(report.steps), report.wallSeconds, report.maxAccel);
  }
  solver->Download(&previous);
  sphxr::sim::HostBoundary walls;  // static walls: fetched once, for --energy
  if (energy) solver->DownloadBoundary(&walls);
  for (int w = 1; w <= static_cast<int>(windows); ++w) {
    int64_t clamped = 0;
    while (solver->Time() < window * w - 1e-9) {
      if (sphxr::Status s = solver->Step(); !s) {
        std::fprintf(stderr, "sphxr_bench_rest: %s\n", s.message().c_str());
        return 1;
      }
      clamped += solver->LastStep().clamped;
      if (solver->Time() > dampFrom && solver->Time() <= dampUntil) {
        // The quench experiment (docs/design/settle.md): every velocity times exp(-rate dt) after each step.
        HostFluid& f = damped;  // reused: no allocation per step
        solver->Download(&f);
        const float k = std::exp(-static_cast<float>(dampRate) * solver->LastStep().dt);
        for (Vec4& v : f.velocity) { v.x *= k; v.y *= k; v.z *= k; }
        if (sphxr::Status s = solver->Upload(f); !s) {
          std::fprintf(stderr, "sphxr_bench_rest: %s\n", s.message().c_str());
          return 1;
        }
      }
    }
    HostFluid current;
    solver->Download(&current);
    std::unordered_map<uint32_t, Vec4> start;
    for (size_t i = 0; i < previous.size(); ++i) start[previous.id[i]] = previous.position[i];
    std::vector<float> drift;
    double speedSum = 0.0;
    float speedMax = 0.0f;
    for (size_t i = 0; i < current.size(); ++i) {
      const Vec4 a = current.position[i], b = start.at(current.id[i]);
      drift.push_back(std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)) / dx);
      const Vec4 u = current.velocity[i];
      const float speed = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
      speedSum += speed;
      speedMax = std::max(speedMax, speed);
    }
    if (detail && w == static_cast<int>(windows)) {
      std::vector<std::pair<float, size_t>> worst;
      for (size_t i = 0; i < drift.size(); ++i) worst.push_back({drift[i], i});
      std::sort(worst.rbegin(), worst.rend());
      for (int k = 0; k < 12; ++k) {
        const Vec4 q = current.position[worst[k].second];
        std::printf("  drift %.3f at x %.2f y %.2f z %.2f (spacings from tank min)\n", worst[k].first,
                    (q.x - scene.setup.tank.min.x) / dx, (q.y - scene.setup.tank.min.y) / dx, (q.z - scene.setup.tank.min.z) / dx);
      }
    }
    std::sort(drift.begin(), drift.end());
    std::printf("| %.2f-%.2f | %.3f | %.3f | %.3f | %.2f | %.2f | %lld |\n", window * (w - 1), window * w,
                drift[drift.size() / 2], drift[drift.size() * 9 / 10], drift.back(),
                1e3 * speedSum / static_cast<double>(current.size()), 1e3 * speedMax, static_cast<long long>(clamped));
    std::fflush(stdout);
    if (energy) {
      const sphxr::sim::EnergySummary e = sphxr::sim::SphEnergy(solver->Scene(), solver->ParticleMass(), current, walls);
      if (w == 1) energyStart = e.Total();
      std::printf("  energy %.9e J (change since the first window %+.4e J): kinetic %.4e, gravity %.9e, fluid %.6e, walls %.6e\n",
                  e.Total(), e.Total() - energyStart, e.kinetic, e.gravity, e.fluid, e.walls);
    }
    previous = std::move(current);
  }
  // Layer pressures at the end, each particle against rho0 g times its own depth.
  const float rho0 = scene.setup.params.restDensity, g = -scene.setup.gravity.y;
  float top = -1e30f;
  for (const Vec4& p : previous.position) top = std::max(top, p.y);
  const float surface = top + 0.5f * dx;
  const float depthTotal = surface - scene.setup.tank.min.y;
  const int layers = static_cast<int>(depthTotal / dx) + 1;
  std::vector<double> pressure(layers, 0.0), reference(layers, 0.0), count(layers, 0.0);
  for (size_t i = 0; i < previous.size(); ++i) {
    const float depth = surface - previous.position[i].y;
    const int l = static_cast<int>(depth / dx);
    if (l < 0 || l >= layers) continue;
    pressure[l] += previous.pressure[i];
    reference[l] += rho0 * g * depth;
    count[l] += 1.0;
  }
  std::printf("\n| layer from the surface | depth (m) | particles | p / (rho0 g depth) |\n|---:|---:|---:|---:|\n");
  double worst = 0.0;
  for (int l = 0; l < layers; ++l) {
    if (count[l] < 20) continue;
    const double depth = (l + 0.5) * dx, ratio = pressure[l] / reference[l];
    if (depth >= 0.2 * depthTotal) worst = std::max(worst, std::fabs(ratio - 1.0));
    std::printf("| %d | %.4f | %.0f | %.4f |", l, depth, count[l], ratio);
    if (detail) {
      double ys = 0, n = 0, pin = 0, rin = 0, nin = 0;
      for (size_t i = 0; i < previous.size(); ++i) {
        const Vec4 q = previous.position[i];
        if (static_cast<int>((surface - q.y) / dx) != l) continue;
        ys += q.y; n += 1;
        const bool interior = q.x > scene.setup.tank.min.x + 2.5f * dx && q.x < scene.setup.tank.max.x - 2.5f * dx &&
                              q.z > scene.setup.tank.min.z + 2.5f * dx && q.z < scene.setup.tank.max.z - 2.5f * dx;
        if (interior) { pin += previous.pressure[i] / (rho0 * g * (surface - q.y)); rin += previous.density[i]; nin += 1; }
      }
      std::printf(" y/dx %.3f interior p %.4f rho-1 %.1f ppm (%g)", ys / n / dx, pin / nin, (rin / nin / rho0 - 1) * 1e6, nin);
    }
    std::printf("\n");
  }
  std::printf("\nworst |p / (rho0 g depth) - 1| over the lower 80 %% of the depth: %.2f %%\n", 100.0 * worst);
  return 0;
}
