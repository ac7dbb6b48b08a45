// sphxr_bench_blocks: the CPU density blocks fitted to the particles (Morton boxes of up to 4 x 4 x 4
// cells where the water is sparse, crowded pairs cut per cell; cpu/blocks.h BlockBoxOf) against the
// layout before them (every block from a pair of cells along x; sim/src/backend.h UsePairDensityBlocks).
//
// Two solvers of one scene, one per layout, stepped in lock-step: one step of each in turn, the first
// of each step alternating, so that both see the same machine (this VM's speed swings 1.5-3x between
// runs, and whole runs in turn cannot resolve a few per cent). Per segment of simulated time: each
// layout's mean density-stage and whole-step milliseconds per step (Solver::GetTotals), and their
// ratios. The two layouts give the same numbers bit for bit, so both solvers walk the same states;
// at the end the bench compares every fluid field of the two and exits 1 if any bit differs. With
// --control both solvers use the boxes: the ratios then show how far two solvers doing the same work
// differ here (their arrays sit at different addresses), the floor under which a ratio means nothing.
//
// The benchmark reports; it never fails on a speed (speed is not asserted anywhere).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "backend.h"  // sim/src: UsePairDensityBlocks
#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::bench {
namespace {

struct Args {
  std::string scene = SPHXR_SCENES_DIR "/dam_break_1m.json";
  double time = 0.5;      // s of simulated time
  double segment = 0.1;   // s per reported segment
  int threads = 2;
  std::string reuse = "off";  // off, or a preset
  bool control = false;       // both solvers with the fitted boxes: the noise floor of the pairing
  bool help = false;
};

const char* kUsage =
    "usage: sphxr_bench_blocks [--scene FILE] [--time S] [--segment S] [--threads N] [--reuse PRESET]\n"
    "  --scene FILE    the scene (default scenes/dam_break_1m.json)\n"
    "  --time S        simulated seconds to run (default 0.5)\n"
    "  --segment S     simulated seconds per reported row (default 0.1)\n"
    "  --threads N     CPU threads of each solver (default 2)\n"
    "  --reuse PRESET  off (default), accurate, balanced or fast: both solvers reuse alike\n"
    "  --control       both solvers with the fitted boxes (the 'pairs' columns then time a second copy of\n"
    "                  the same work: how far two solvers doing the same work differ on this machine)\n";

bool ParseArgs(int argc, char** argv, Args* out) {
  const char* program = "sphxr_bench_blocks";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char** v) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: %s needs a value\n", program, a.c_str());
        return false;
      }
      *v = argv[++i];
      return true;
    };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") {
      out->help = true;
    } else if (a == "--control") {
      out->control = true;
    } else if (a == "--scene") {
      if (!value(&v)) return false;
      out->scene = v;
    } else if (a == "--time" || a == "--segment") {
      if (!value(&v)) return false;
      double x = 0.0;
      if (!ParseNumber(v, &x) || x <= 0.0 || x > 1e4) {
        std::fprintf(stderr, "%s: %s %s: must be a number of seconds above 0\n", program, a.c_str(), v);
        return false;
      }
      (a == "--time" ? out->time : out->segment) = x;
    } else if (a == "--threads") {
      if (!value(&v)) return false;
      if (!IntegerOption(program, a, v, 1, 1024, &out->threads)) return false;
    } else if (a == "--reuse") {
      if (!value(&v)) return false;
      sim::ReuseParams probe;
      if (std::string(v) != "off" && !sim::ApplyReusePreset(v, &probe)) {
        std::fprintf(stderr, "%s: --reuse %s: must be off, accurate, balanced or fast\n", program, v);
        return false;
      }
      out->reuse = v;
    } else {
      std::fprintf(stderr, "%s: unknown argument %s\n%s", program, a.c_str(), kUsage);
      return false;
    }
  }
  return true;
}

/// Cumulative seconds of one solver: the density stage and the whole step.
struct Clock {
  double density = 0.0, step = 0.0;
  int64_t steps = 0;
};
Clock Read(const sim::Solver& s) {
  const sim::Totals& t = s.GetTotals();
  return Clock{t.stageSeconds[static_cast<int>(sim::Stage::kDensity)], t.stepSeconds, t.steps};
}

/// The first fluid field whose bits differ between a and b, or "" when none does.
std::string FirstDifference(const sim::HostFluid& a, const sim::HostFluid& b) {
  std::string diff;
#define SPHXR_COMPARE_FIELD(type, name)                                                            \
  if (diff.empty() && (a.name.size() != b.name.size() ||                                           \
                       (!a.name.empty() && std::memcmp(a.name.data(), b.name.data(),               \
                                                       a.name.size() * sizeof(type)) != 0))) {     \
    diff = #name;                                                                                  \
  }
  SPHXR_FLUID_FIELDS(SPHXR_COMPARE_FIELD)
#undef SPHXR_COMPARE_FIELD
  return diff;
}

int Main(int argc, char** argv) {
  Args args;
  if (!ParseArgs(argc, argv, &args)) return 2;
  if (args.help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  app::SceneFile scene;
  if (Status s = app::LoadScene(args.scene, &scene); !s) {
    std::fprintf(stderr, "sphxr_bench_blocks: %s\n", s.message().c_str());
    return 1;
  }
  if (args.reuse != "off") {
    sim::ApplyReusePreset(args.reuse, &scene.setup.reuse);
  } else {
    scene.setup.reuse.enabled = false;
  }
  // [0]: the fitted boxes (the default), [1]: pairs only.
  std::unique_ptr<sim::Solver> solver[2];
  for (int k = 0; k < 2; ++k) {
    sim::SolverConfig config;
    config.device = sim::Device::kCpu;
    config.threads = args.threads;
    if (Status s = sim::Solver::Create(scene.setup, config, &solver[k]); !s) {
      std::fprintf(stderr, "sphxr_bench_blocks: %s\n", s.message().c_str());
      return 1;
    }
    if (k == 1 && !args.control) solver[k]->BackendForTests()->UsePairDensityBlocks();
  }
  std::printf("sphxr_bench_blocks: %s, %d fluid particles, %.3g s, reuse %s, %d thread(s)%s\n", args.scene.c_str(),
              solver[0]->FluidCount(), args.time, args.reuse.c_str(), args.threads,
              args.control ? ", CONTROL: both solvers use the boxes" : "");
  std::printf("machine: %s, %d cores, load %.2f at start, %s\n", CpuModel().c_str(), CpuCount(), LoadAverage(),
              UtcTimestamp().c_str());
  std::printf("\nms per step, mean over each segment; both layouts stepped in lock-step\n\n");
  std::printf("| segment, s | steps | density, boxes | density, pairs | pairs / boxes | step, boxes | step, pairs | pairs / boxes |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  std::fflush(stdout);

  Clock start[2] = {Read(*solver[0]), Read(*solver[1])};
  Clock first[2] = {start[0], start[1]};
  double segmentStart = solver[0]->Time();
  bool boxesFirst = true;
  auto row = [&](const char* label, const Clock (&from)[2]) {
    Clock now[2] = {Read(*solver[0]), Read(*solver[1])};
    double density[2], step[2];
    const int64_t steps = now[0].steps - from[0].steps;
    for (int k = 0; k < 2; ++k) {
      const double n = static_cast<double>(std::max<int64_t>(1, now[k].steps - from[k].steps));
      density[k] = 1e3 * (now[k].density - from[k].density) / n;
      step[k] = 1e3 * (now[k].step - from[k].step) / n;
    }
    std::printf("| %s | %lld | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", label, static_cast<long long>(steps),
                density[0], density[1], density[1] / density[0], step[0], step[1], step[1] / step[0]);
    std::fflush(stdout);
  };
  while (solver[0]->Time() < args.time - 1e-9) {
    for (int k = 0; k < 2; ++k) {
      sim::Solver& s = *solver[boxesFirst ? k : 1 - k];
      if (Status st = s.Step(); !st) {
        std::fprintf(stderr, "sphxr_bench_blocks: %s\n", st.message().c_str());
        return 1;
      }
    }
    boxesFirst = !boxesFirst;
    if (solver[0]->Time() != solver[1]->Time()) {
      std::fprintf(stderr, "sphxr_bench_blocks: the layouts' clocks parted at t = %.6f s (%.6f s): their states differ\n",
                   solver[0]->Time(), solver[1]->Time());
      return 1;
    }
    const double t = solver[0]->Time();
    if (t >= segmentStart + args.segment - 1e-9 || t >= args.time - 1e-9) {
      char label[64];
      std::snprintf(label, sizeof label, "%.3f-%.3f", segmentStart, t);
      row(label, start);
      start[0] = Read(*solver[0]);
      start[1] = Read(*solver[1]);
      segmentStart = t;
    }
  }
  row("whole run", first);

  sim::HostFluid fluid[2];
  solver[0]->Download(&fluid[0]);
  solver[1]->Download(&fluid[1]);
  const std::string diff = FirstDifference(fluid[0], fluid[1]);
  if (!diff.empty()) {
    std::fprintf(stderr, "sphxr_bench_blocks: the layouts' fluid field '%s' differs at t = %.6f s: the boxes must "
                 "give the pairs' numbers bit for bit\n", diff.c_str(), solver[0]->Time());
    return 1;
  }
  std::printf("\nevery fluid field bit for bit the same in both layouts at t = %.6f s; load %.2f at the end\n",
              solver[0]->Time(), LoadAverage());
  return 0;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) { return sphxr::bench::Main(argc, argv); }
