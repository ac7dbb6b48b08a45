// sphxr_bench_diffuse: what the diffuse particles' potentials (Ihmsen et al. 2012, sim/src/stages/diffuse.h)
// reach in a scene, so that their ranges can be chosen for it, and what the stage costs. Runs the scene
// with solver.diffuse on for --time simulated seconds and every --every seconds computes, on the host
// and independently of the stage (a HostGrid over a download of the fluid), each fluid particle's
// trapped-air sum v_diff (m/s), its wave-crest curvature where it moves along its normal, and its
// kinetic energy per kg; prints their 99th percentile and maximum, the diffuse particles by kind, and
// the diffuse stage's share of the step. Measures, never asserts (docs/dev/benchmarking.md).
//
//   sphxr_bench_diffuse --scene scenes/stir.json [--method pbf] [--time 2] [--every 0.25] [--threads 1]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/diffuse.h"
#include "sphxr/sim/host_grid.h"
#include "sphxr/sim/solver.h"

namespace sphxr {
namespace {

using bench::CpuModel;
using bench::IntegerOption;
using bench::LoadAverage;
using bench::ParseNumber;

struct Args {
  std::string scene = SPHXR_SCENES_DIR "/stir.json";
  std::string method;
  double time = 2.0, every = 0.25;
  int threads = 1;
};

float Percentile(std::vector<float> v, double q) {
  if (v.empty()) return 0.0f;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

/// The three quantities of [IAAT12] eq. 2, 4-6 and 7 for every fluid particle, by brute force over a HostGrid.
void Potentials(const sim::HostFluid& f, float h, float volume, int bubbleAbove, std::vector<float>* trapped,
                std::vector<float>* crest, std::vector<float>* energy) {
  sim::Vec3 lo, hi;
  sim::BoundingBox({&f.position}, &lo, &hi);
  const sim::HostGrid grid(f.position, lo, hi, h);
  const size_t n = f.size();
  std::vector<sim::Vec3> normal(n);
  std::vector<int> count(n, 0);
  const float sigma = 8.0f / (3.14159265f * h * h * h);
  for (size_t i = 0; i < n; ++i) {
    const sim::Vec3 xi = Xyz(f.position[i]);
    sim::Vec3 grad;
    grid.ForEachNear(xi, [&](uint32_t j) {
      const sim::Vec3 d = xi - Xyz(f.position[j]);
      const float r = Length(d);
      if (j == i || r >= h) return;
      ++count[i];
      const float q = r / h;  // cubic spline dW/dr / r
      const float g =
          q <= 0.5f ? 6.0f * sigma / (h * h) * (3.0f * q - 2.0f) : -6.0f * sigma / h * (1 - q) * (1 - q) / r;
      grad += d * g;
    });
    const sim::Vec3 nn = grad * -volume;
    const float len = Length(nn);
    normal[i] = len * h > 1e-3f ? nn * (1.0f / len) : sim::Vec3{};
  }
  trapped->assign(n, 0.0f);
  crest->assign(n, 0.0f);
  energy->assign(n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    const sim::Vec3 xi = Xyz(f.position[i]), vi = Xyz(f.velocity[i]);
    const bool surface = count[i] <= bubbleAbove && Dot(normal[i], normal[i]) > 0.0f;
    float ta = 0.0f, k = 0.0f;
    grid.ForEachNear(xi, [&](uint32_t j) {
      const sim::Vec3 d = xi - Xyz(f.position[j]);
      const float r = Length(d);
      if (j == i || r >= h || r <= 0.0f) return;
      const float w = 1.0f - r / h;
      const sim::Vec3 v = vi - Xyz(f.velocity[j]);
      const float s = Length(v);
      if (s > 0.0f) ta += s * (1.0f - Dot(v, d) / (s * r)) * w;
      if (surface && Dot(d, normal[i]) > 0.0f) k += (1.0f - Dot(normal[i], normal[j])) * w;
    });
    const float speed = Length(vi);
    (*trapped)[i] = ta;
    (*crest)[i] = speed > 0.0f && Dot(vi, normal[i]) / speed >= 0.6f ? k : 0.0f;
    (*energy)[i] = 0.5f * speed * speed;
  }
}

int Main(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: missing value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    double v = 0.0;
    if (a == "--scene")
      args.scene = next();
    else if (a == "--method")
      args.method = next();
    else if ((a == "--time" || a == "--every") && ParseNumber(next(), &v) && v > 0.0)
      (a == "--time" ? args.time : args.every) = v;
    else if (a == "--threads") {
      if (!IntegerOption("sphxr_bench_diffuse", a, next(), 1, 256, &args.threads)) return 2;
    } else {
      std::fprintf(stderr,
                   "usage: sphxr_bench_diffuse [--scene FILE] [--method wcsph|dfsph|pbf] [--time S] [--every S] "
                   "[--threads N]\n");
      return 2;
    }
  }
  SetLogLevel(LogLevel::kWarn);
  app::SceneFile scene;
  if (Status s = app::LoadScene(args.scene, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  if (!args.method.empty() && !sim::ParseSolverMethod(args.method, &scene.setup.method)) {
    std::fprintf(stderr, "--method %s: not a solver\n", args.method.c_str());
    return 2;
  }
  scene.setup.params.diffuse = 1.0f;
  app::SimulationConfig config;
  config.solver.device = sim::Device::kCpu;
  config.solver.threads = args.threads;
  std::unique_ptr<app::Simulation> simulation;
  if (Status s = app::Simulation::Create(app::SimSceneFromFile(scene), config, &simulation); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  const sim::Solver& solver = simulation->Solver();
  const sim::SolverParams& p = scene.setup.params;
  const float h = p.spacing * p.supportFactor;
  const float volume = p.spacing * p.spacing * p.spacing;
  std::printf("# %s, %s, %d fluid particles, %s, load %.2f\n", args.scene.c_str(),
              sim::SolverMethodName(scene.setup.method), solver.FluidCount(), CpuModel().c_str(), LoadAverage());
  std::printf("# the ranges: trapped air %g-%g m/s, wave crest %g-%g, energy %g-%g J/kg\n", p.diffuseTrappedAirMin,
              p.diffuseTrappedAirMax, p.diffuseWaveCrestMin, p.diffuseWaveCrestMax, p.diffuseEnergyMin,
              p.diffuseEnergyMax);
  std::printf("%8s %10s %10s %10s %10s %10s %10s %7s %7s %7s\n", "t_s", "ta_p99", "ta_max", "wc_p99", "wc_max",
              "ek_p99", "ek_max", "spray", "foam", "bubble");
  double next = args.every;
  while (solver.Time() < args.time) {
    if (Status s = simulation->Step(); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return 1;
    }
    if (solver.Time() + 1e-9 < next) continue;
    next += args.every;
    sim::HostFluid f;
    solver.Download(&f);
    std::vector<float> ta, wc, ek;
    Potentials(f, h, volume, static_cast<int>(p.diffuseBubbleAbove), &ta, &wc, &ek);
    sim::HostDiffuse d;
    solver.DownloadDiffuse(&d);
    int kinds[3] = {0, 0, 0};
    for (const sim::Vec4& v : d.velocity) ++kinds[static_cast<int>(sim::DiffuseKindOf(v))];
    std::printf("%8.3f %10.4g %10.4g %10.4g %10.4g %10.4g %10.4g %7d %7d %7d\n", solver.Time(), Percentile(ta, 0.99),
                Percentile(ta, 1.0), Percentile(wc, 0.99), Percentile(wc, 1.0), Percentile(ek, 0.99),
                Percentile(ek, 1.0), kinds[0], kinds[1], kinds[2]);
  }
  const sim::Totals& t = solver.GetTotals();
  const double diffuseMs = 1e3 * t.stageSeconds[static_cast<int>(sim::Stage::kDiffuse)] / static_cast<double>(t.steps);
  const double stepMs = 1e3 * t.stepSeconds / static_cast<double>(t.steps);
  std::printf("# %lld steps: %.3f ms per step, of it the diffuse stage %.3f ms (%.1f %%)\n",
              static_cast<long long>(t.steps), stepMs, diffuseMs, stepMs > 0 ? 100.0 * diffuseMs / stepMs : 0.0);
  return 0;
}

}  // namespace
}  // namespace sphxr

int main(int argc, char** argv) { return sphxr::Main(argc, argv); }
