// sphxr_bench_paddles: the cost of paddles per step, on scenes/stir.json (a tank of water stirred by one
// scripted paddle) against the same tank without the paddle ("paddles" section dropped), side by side.
//
// Rounds alternate the two configurations (with, without, with, without, ...) so that a change of the
// machine's load hits both alike. Per configuration and round: warm-up steps, then measured steps, each
// timed around everything a step costs (app::Simulation::Step: with the paddle, the frame's BeginFrame
// when one is due, Solver::Step, PaddleSystem::AfterStep). Reported: the median over rounds of the per-round median ms
// per step, the per-stage split (the "bodies" stage is the paddles' own work: placing and sorting their
// particles, the reaction, the push-out; their terms inside the density and force loops show as the
// difference of those stages), the mean time step (the paddle's speed enters the CFL bound) and so the
// cost per simulated second. The benchmark reports; it never fails on a time.
#include <omp.h>

#include <chrono>
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
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/solver.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::bench {
namespace {

constexpr int kStages = static_cast<int>(sim::Stage::kCount);

struct Args {
  std::string scene = SPHXR_SCENES_DIR "/stir.json";
  int rounds = 3, warmup = 100, measured = 300, threads = 0;
  float spacing = 0.0f;
};

struct Round {
  double medianMs = 0.0;
  double stageMs[kStages] = {};
  double meanDt = 0.0;
  int fluid = 0, boundary = 0, paddleParticles = 0;
  int64_t pushed = 0;
};

bool RunRound(const Args& args, bool withPaddle, Round* r) {
  app::SceneFile scene;
  if (Status s = app::LoadScene(args.scene, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  if (args.spacing > 0.0f) scene.setup.params.spacing = args.spacing;
  if (withPaddle && scene.paddles.empty()) {
    std::fprintf(stderr, "%s has no paddles section\n", args.scene.c_str());
    return false;
  }
  app::SimScene run = app::SimSceneFromFile(scene);
  if (!withPaddle) run.paddles.clear();
  app::SimulationConfig config;
  config.solver.device = sim::Device::kCpu;
  config.solver.threads = args.threads;
  std::unique_ptr<app::Simulation> simulation;
  if (Status s = app::Simulation::Create(run, config, &simulation); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  const sim::Solver* solver = &simulation->Solver();
  if (const interaction::PaddleSystem* paddles = simulation->Paddles()) {
    for (int k = 0; k < paddles->Count(); ++k) r->paddleParticles += paddles->ParticleCount(k);
  }
  r->fluid = solver->FluidCount();
  r->boundary = solver->BoundaryCount();
  auto step = [&]() -> bool {
    if (Status s = simulation->Step(); !s) {
      std::fprintf(stderr, "the run failed at t = %g s\n", solver->Time());
      return false;
    }
    return true;
  };
  for (int i = 0; i < args.warmup; ++i) {
    if (!step()) return false;
  }
  const sim::Totals before = solver->GetTotals();
  const double t0 = solver->Time();
  std::vector<double> ms;
  for (int i = 0; i < args.measured; ++i) {
    const auto a = std::chrono::steady_clock::now();
    if (!step()) return false;
    ms.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  const sim::Totals after = solver->GetTotals();
  r->medianMs = Median(ms);
  for (int s = 0; s < kStages; ++s) r->stageMs[s] = 1e3 * (after.stageSeconds[s] - before.stageSeconds[s]) / args.measured;
  r->meanDt = (solver->Time() - t0) / args.measured;
  r->pushed = after.pushedOutEvents - before.pushedOutEvents;
  return true;
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
    // A bad number ends the program with one line naming it, before any scene is loaded.
    auto integer = [&](long lo, long hi, int* out) {
      if (!IntegerOption("sphxr_bench_paddles", a, next(), lo, hi, out)) std::exit(2);
    };
    if (a == "--scene") args.scene = next();
    else if (a == "--rounds") integer(1, 1000000, &args.rounds);
    else if (a == "--warmup") integer(0, 1000000, &args.warmup);
    else if (a == "--measured") integer(1, 1000000, &args.measured);
    else if (a == "--threads") integer(0, 1024, &args.threads);  // 0: all cores
    else if (a == "--spacing") {
      const char* v = next();
      double h = 0.0;
      if (!ParseNumber(v, &h) || !(h > 0.0 && h < 1.0)) {
        std::fprintf(stderr, "sphxr_bench_paddles: --spacing %s: must be a number between 0 and 1 (m)\n", v);
        std::exit(2);
      }
      args.spacing = static_cast<float>(h);
    } else if (a == "--quick") args.rounds = 1, args.warmup = 20, args.measured = 40;
    else {
      std::fprintf(stderr,
                   "usage: sphxr_bench_paddles [--scene FILE] [--rounds R] [--warmup N] [--measured N] [--threads T]\n"
                   "                           [--spacing H] [--quick]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  SetLogLevel(LogLevel::kWarn);
  const double loadStart = LoadAverage();
  std::vector<Round> with, without;
  for (int k = 0; k < args.rounds; ++k) {
    Round a, b;
    std::fprintf(stderr, "round %d/%d ...\n", k + 1, args.rounds);
    if (!RunRound(args, true, &a) || !RunRound(args, false, &b)) return 1;
    with.push_back(a);
    without.push_back(b);
  }
  const double loadEnd = LoadAverage();
  auto median = [](const std::vector<Round>& rounds, auto field) {
    std::vector<double> v;
    for (const Round& r : rounds) v.push_back(field(r));
    return Median(v);
  };
  const double msWith = median(with, [](const Round& r) { return r.medianMs; });
  const double msWithout = median(without, [](const Round& r) { return r.medianMs; });
  const double dtWith = median(with, [](const Round& r) { return r.meanDt; });
  const double dtWithout = median(without, [](const Round& r) { return r.meanDt; });

  std::printf("## sphxr_bench_paddles: %s\n\n", args.scene.c_str());
  std::printf("- %s, %d cpus, %d threads; load average %.2f before, %.2f after; %s\n", CpuModel().c_str(), CpuCount(),
              args.threads > 0 ? args.threads : omp_get_num_procs(), loadStart, loadEnd, UtcTimestamp().c_str());
  std::printf("- %d round(s), each: with paddle then without, %d warm-up + %d measured steps\n\n", args.rounds,
              args.warmup, args.measured);
  std::printf("| configuration | fluid | boundary (static + paddle) | median ms/step | mean dt (ms) | ms per simulated s |\n");
  std::printf("|---|---:|---:|---:|---:|---:|\n");
  std::printf("| with paddle | %d | %d + %d | %.3f | %.4f | %.0f |\n", with[0].fluid, with[0].boundary,
              with[0].paddleParticles, msWith, 1e3 * dtWith, msWith / dtWith);
  std::printf("| without | %d | %d | %.3f | %.4f | %.0f |\n", without[0].fluid, without[0].boundary, msWithout,
              1e3 * dtWithout, msWithout / dtWithout);
  std::printf("\nratio with / without: %.3f per step, %.3f per simulated second (the paddle's speed lowers dt)\n\n",
              msWith / msWithout, (msWith / dtWith) / (msWithout / dtWithout));
  std::printf("Per-stage ms per step (median over rounds):\n\n| configuration |");
  for (int s = 0; s < kStages; ++s) std::printf(" %s |", sim::StageName(static_cast<sim::Stage>(s)));
  std::printf("\n|---|");
  for (int s = 0; s < kStages; ++s) std::printf("---:|");
  std::printf("\n");
  for (const auto* rounds : {&with, &without}) {
    std::printf("| %s |", rounds == &with ? "with paddle" : "without");
    for (int s = 0; s < kStages; ++s) std::printf(" %.3f |", median(*rounds, [s](const Round& r) { return r.stageMs[s]; }));
    std::printf("\n");
  }
  std::printf("\nfluid particles pushed out of the paddle: %lld over the measured steps of round 1\n",
              static_cast<long long>(with[0].pushed));
  return 0;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) { return sphxr::bench::Main(argc, argv); }
