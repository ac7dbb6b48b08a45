// sphxr_bench_reuse_settled: does reuse pay off once a deep pool is really calm?
//
// scenes/deep_tank.json's pool (its first fluid block) is settled alone with reuse off for --settle
// simulated seconds, at a raised viscosity (--settle-viscosity) so the lattice's rearrangement dies out
// sooner. Its state is then copied, by particle id, into the scene (with the dropped block when --drop
// is given, otherwise the pool alone) and run for --time seconds twice from that same state: reuse off,
// then the preset. Every
// --report steps it prints the fraction that computed, the maximum speed and the mean compression; at
// the end the mean step time of each run. --probe prints the acceleration of four interior particles for
// 16 steps after settling (how smooth the forces of a calm pool are) and stops.
// The two runs follow each other, so their step times are not side by side: sphxr_bench_reuse pairs
// runs in lock-step; this program answers whether particles go inactive at all.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/sim/solver.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace {

using sphxr::sim::HostFluid;
using sphxr::sim::Solver;

const char* kUsage =
    "usage: sphxr_bench_reuse_settled [--scene FILE] [--settle S] [--settle-viscosity V] [--time T] [--preset P]\n"
    "                                 [--fixed-dt DT] [--drop] [--threads N] [--report K] [--probe]\n"
    "  --scene FILE          default scenes/deep_tank.json; its first fluid block is the pool\n"
    "  --settle S            simulated seconds of settling the pool alone, reuse off (default 2)\n"
    "  --settle-viscosity V  viscosity and wall viscosity while settling (default 0.5; the scene's after)\n"
    "  --time T              simulated seconds of each measured run (default 0.3)\n"
    "  --preset P            accurate | balanced | fast (default balanced)\n"
    "  --fixed-dt DT         override the scene's fixed time step (settling and both runs)\n"
    "  --drop                keep the scene's other blocks (deep_tank: the dropped block)\n"
    "  --threads N           CPU threads (default 0 = all cores)\n"
    "  --report K            print a line every K steps (default 100)\n"
    "  --probe               print four interior particles' accelerations for 16 steps after settling, then stop\n";

bool Fail(const sphxr::Status& s) {
  if (s) return false;
  std::fprintf(stderr, "sphxr_bench_reuse_settled: %s\n", s.message().c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath = std::string(SPHXR_SCENES_DIR) + "/deep_tank.json";
  double settle = 2.0, settleViscosity = 0.5, runTime = 0.3, fixedDt = 0.0;
  std::string preset = "balanced";
  bool drop = false, probe = false;
  double threads = 0, report = 100;
  for (int a = 1; a < argc; ++a) {
    auto value = [&](double* out, bool positive) {
      if (a + 1 >= argc || !sphxr::bench::ParseNumber(argv[a + 1], out) || (positive ? *out <= 0 : *out < 0)) {
        std::fprintf(stderr, "sphxr_bench_reuse_settled: %s wants a %s number\n%s", argv[a],
                     positive ? "positive" : "non-negative", kUsage);
        std::exit(2);
      }
      ++a;
    };
    if (!std::strcmp(argv[a], "--scene") && a + 1 < argc) scenePath = argv[++a];
    else if (!std::strcmp(argv[a], "--preset") && a + 1 < argc) preset = argv[++a];
    else if (!std::strcmp(argv[a], "--settle")) value(&settle, false);
    else if (!std::strcmp(argv[a], "--settle-viscosity")) value(&settleViscosity, false);
    else if (!std::strcmp(argv[a], "--time")) value(&runTime, true);
    else if (!std::strcmp(argv[a], "--fixed-dt")) value(&fixedDt, true);
    else if (!std::strcmp(argv[a], "--threads")) value(&threads, false);
    else if (!std::strcmp(argv[a], "--report")) value(&report, true);
    else if (!std::strcmp(argv[a], "--drop")) drop = true;
    else if (!std::strcmp(argv[a], "--probe")) probe = true;
    else {
      std::fprintf(stderr, "%s", kUsage);
      return !std::strcmp(argv[a], "--help") ? 0 : 2;
    }
  }
  sphxr::app::SceneFile file;
  if (Fail(sphxr::app::LoadScene(scenePath, &file))) return 1;
  sphxr::sim::SceneSetup scene = file.setup;
  if (scene.fluid.empty()) return std::fprintf(stderr, "sphxr_bench_reuse_settled: the scene has no fluid\n"), 1;
  scene.reuse = {};
  if (fixedDt > 0) scene.params.fixedDt = static_cast<float>(fixedDt);
  if (!drop) scene.fluid.resize(1);
  sphxr::sim::ReuseParams reuse;
  if (!sphxr::sim::ApplyReusePreset(preset, &reuse)) {
    return std::fprintf(stderr, "sphxr_bench_reuse_settled: unknown preset '%s'\n", preset.c_str()), 2;
  }
  sphxr::sim::SolverConfig config;
  config.threads = static_cast<int>(threads);
  const int every = static_cast<int>(report);

  // Settle the pool alone. Particle ids follow the sampling order, block by block, so the pool's ids are
  // the same in the pool-only and the full scene.
  sphxr::sim::SceneSetup pool = scene;
  pool.fluid.resize(1);
  pool.params.viscosity = pool.params.boundaryViscosity = static_cast<float>(settleViscosity);
  std::unique_ptr<Solver> settler;
  if (Fail(Solver::Create(pool, config, &settler))) return 1;
  std::printf("settling %lld pool particles for %g s at viscosity %g\n",
              static_cast<long long>(settler->FluidCount()), settle, settleViscosity);
  float vmax = 0.0f;
  for (int step = 1; settler->Time() < settle - 1e-9; ++step) {
    if (Fail(settler->Step())) return 1;
    vmax = std::max(vmax, settler->LastStep().maxSpeed);
    if (step % (every * 3) == 0) {
      std::printf("  settle t = %.2f s: max speed %.4f m/s\n", settler->Time(), vmax);
      vmax = 0.0f;
    }
  }
  HostFluid settled, state;
  settler->Download(&settled);
  {
    std::unique_ptr<Solver> full;
    if (Fail(Solver::Create(scene, config, &full))) return 1;
    full->Download(&state);
    std::vector<size_t> byId(state.size());
    for (size_t i = 0; i < state.size(); ++i) byId[state.id[i]] = i;
    for (size_t i = 0; i < settled.size(); ++i) {
      const size_t j = byId[settled.id[i]];
#define SPHXR_COPY_FIELD(type, name) state.name[j] = settled.name[i];
      SPHXR_FLUID_FIELDS(SPHXR_COPY_FIELD)
#undef SPHXR_COPY_FIELD
    }
  }

  if (probe) {  // reuse off from the settled state, four interior particles' accelerations
    std::unique_ptr<Solver> solver;
    if (Fail(Solver::Create(scene, config, &solver)) || Fail(solver->Upload(state))) return 1;
    const uint32_t ids[4] = {10007, 20000, 30123, 40500};
    for (int step = 0; step < 16; ++step) {
      if (Fail(solver->Step())) return 1;
      HostFluid h;
      solver->Download(&h);
      std::printf("step %2d:", step);
      for (size_t i = 0; i < h.size(); ++i) {
        for (uint32_t id : ids) {
          if (h.id[i] == id) std::printf("  #%u a = (%.2f %.2f %.2f)", id, h.acceleration[i].x, h.acceleration[i].y, h.acceleration[i].z);
        }
      }
      std::printf("  m/s^2\n");
    }
    return 0;
  }

  double meanMs[2] = {0, 0};
  for (int mode = 0; mode < 2; ++mode) {
    std::unique_ptr<Solver> solver;
    if (Fail(Solver::Create(scene, config, &solver)) || Fail(solver->Upload(state))) return 1;
    const char* name = mode ? preset.c_str() : "off";
    if (mode == 1 && Fail(solver->SetReuse(reuse))) return 1;
    const double t0 = solver->Time();
    double ms = 0.0, active = 0.0, windowActive = 0.0;
    float windowSpeed = 0.0f;
    int steps = 0, windowSteps = 0;
    while (solver->Time() < t0 + runTime - 1e-9) {
      const auto begin = std::chrono::steady_clock::now();
      if (Fail(solver->Step())) return 1;
      ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
      const sphxr::sim::StepInfo& info = solver->LastStep();
      active += info.activeFraction;
      windowActive += info.activeFraction;
      windowSpeed = std::max(windowSpeed, info.maxSpeed);
      ++steps;
      if (++windowSteps == every) {
        std::printf("  %-8s t = %.3f s: computed %.3f, max speed %.3f m/s, mean compression %.3f %%\n", name,
                    solver->Time() - t0, windowActive / windowSteps, windowSpeed, 100.0 * info.meanDensityError);
        windowActive = 0.0;
        windowSpeed = 0.0f;
        windowSteps = 0;
      }
    }
    meanMs[mode] = ms / steps;
    std::printf("%s: %d steps, %.2f ms per step, computed %.3f per step\n", name, steps, meanMs[mode], active / steps);
  }
  std::printf("step time off / %s: %.2f (runs one after the other, not paired)\n", preset.c_str(), meanMs[0] / meanMs[1]);
  return 0;
}
