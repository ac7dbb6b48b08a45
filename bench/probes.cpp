// sphxr_bench_probes: the cost of the probes per step (sphxr/sim/probes.h) on scenes/dam_break_1m.json
// with 20 probes (14 pressure sensors on the walls and the floor, 6 level gauges along the tank), against
// the same scene without probes. The target is under 2 % of a step.
//
// Two solvers step in lock-step (with, without, with, without, ...), so that the machine's load hits both
// alike, each step timed around Solver::Step. Reported: the median ms per step of each, their difference,
// and the probes stage's own time per step (Totals::stageSeconds[kProbes], measured inside the step of the
// solver with probes) as a share of its step. Appends one row to the CSV. It reports; it never fails on
// a time.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::bench {
namespace {

constexpr const char* kHeader =
    "timestamp,cpu,cores,threads,load_before,load_after,scene,fluid,pressure_probes,level_gauges,steps,"
    "step_ms_without,step_ms_with,difference_pct,probe_stage_ms,probe_stage_pct";

/// 20 probes on dam_break_1m's tank ([-2, 2] x [0, 3] x [-0.75, 0.75] m; the column stands at the -x wall).
sim::ProbeSet DamBreakProbes() {
  sim::ProbeSet set;
  for (int k = 0; k < 8; ++k) {  // the far wall, where the surge hits
    const float y = 0.05f + 0.1f * static_cast<float>(k);
    set.pressure.push_back({"far" + std::to_string(k), {2.0f, y, 0.0f}, {1.0f, 0.0f, 0.0f}, {}});
  }
  for (int k = 0; k < 4; ++k) {  // the back wall, behind the column
    const float y = 0.1f + 0.25f * static_cast<float>(k);
    set.pressure.push_back({"back" + std::to_string(k), {-2.0f, y, 0.0f}, {-1.0f, 0.0f, 0.0f}, {}});
  }
  set.pressure.push_back({"floor0", {-1.45f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, {}});
  set.pressure.push_back({"floor1", {1.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, {}});
  for (float x : {-1.5f, -1.0f, -0.5f, 0.0f, 1.0f, 1.9f}) set.level.push_back({"gauge", x, 0.0f, {}, {}});
  return set;
}

int Main(int argc, char** argv) {
  std::string scenePath = SPHXR_SCENES_DIR "/dam_break_1m.json", csv;
  int warmup = 50, measured = 200, threads = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "sphxr_bench_probes: %s: missing value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    auto integer = [&](long lo, long hi, int* out) {
      if (!IntegerOption("sphxr_bench_probes", a, next(), lo, hi, out)) std::exit(2);
    };
    if (a == "--scene") scenePath = next();
    else if (a == "--csv") csv = next();
    else if (a == "--warmup") integer(0, 1000000, &warmup);
    else if (a == "--measured") integer(1, 1000000, &measured);
    else if (a == "--threads") integer(0, 1024, &threads);
    else if (a == "--quick") warmup = 5, measured = 20;
    else {
      std::fprintf(stderr, "usage: sphxr_bench_probes [--scene FILE] [--csv FILE] [--warmup N] [--measured N] "
                           "[--threads T] [--quick]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  std::ofstream out;
  if (!csv.empty()) {
    if (const std::string refusal = OpenCsv(csv, kHeader, true, &out); !refusal.empty()) {
      std::fprintf(stderr, "%s\n", refusal.c_str());
      return 2;
    }
  }
  app::SceneFile scene;
  if (Status s = app::LoadScene(scenePath, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
  config.threads = threads;
  std::unique_ptr<sim::Solver> with, without;
  for (auto* solver : {&with, &without}) {
    if (Status s = sim::Solver::Create(scene.setup, config, solver); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return 1;
    }
  }
  const sim::ProbeSet probes = DamBreakProbes();
  if (Status s = with->SetProbes(probes); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  const double loadBefore = LoadAverage();
  auto step = [](sim::Solver* solver, std::vector<double>* ms) {
    const auto a = std::chrono::steady_clock::now();
    if (Status s = solver->Step(); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      std::exit(1);
    }
    if (ms) ms->push_back(Ms(std::chrono::steady_clock::now() - a));
  };
  for (int i = 0; i < warmup; ++i) step(with.get(), nullptr), step(without.get(), nullptr);
  const sim::Totals before = with->GetTotals();
  std::vector<double> msWith, msWithout;
  for (int i = 0; i < measured; ++i) {
    // Alternate which goes first, so that neither always follows the other's cache traffic.
    if (i % 2 == 0) step(with.get(), &msWith), step(without.get(), &msWithout);
    else step(without.get(), &msWithout), step(with.get(), &msWith);
  }
  const sim::Totals after = with->GetTotals();
  const double loadAfter = LoadAverage();
  const int kProbes = static_cast<int>(sim::Stage::kProbes);
  const double probeMs = 1e3 * (after.stageSeconds[kProbes] - before.stageSeconds[kProbes]) / measured;
  const double mWith = Median(msWith), mWithout = Median(msWithout);
  const double stepMs = 1e3 * (after.stepSeconds - before.stepSeconds) / measured;
  std::printf("%s: %d fluid particles, %zu pressure probes, %zu gauges, %d steps from t = %.3f s\n", scene.name.c_str(),
              with->FluidCount(), probes.pressure.size(), probes.level.size(), measured,
              without->Time() - measured * without->LastStep().dt);
  std::printf("  median step: %.3f ms without probes, %.3f ms with (%+.2f %%)\n", mWithout, mWith,
              100.0 * (mWith / mWithout - 1.0));
  std::printf("  probes stage: %.4f ms per step, %.2f %% of the step with probes (%.3f ms mean)\n", probeMs,
              100.0 * probeMs / stepMs, stepMs);
  const sim::ProbeSample& last = with->LastProbes();
  std::printf("  last reading (t = %.4f s): far0 %.0f Pa, gauge at x = -1.5 m %.3f m\n", last.time, last.pressure[0],
              last.level[0]);
  if (out.is_open()) {
    out << UtcTimestamp() << ',' << CsvField(CpuModel()) << ',' << CpuCount() << ',' << threads << ',' << loadBefore
        << ',' << loadAfter << ',' << scene.name << ',' << with->FluidCount() << ',' << probes.pressure.size() << ','
        << probes.level.size() << ',' << measured << ',' << mWithout << ',' << mWith << ','
        << 100.0 * (mWith / mWithout - 1.0) << ',' << probeMs << ',' << 100.0 * probeMs / stepMs << '\n';
    out.flush();
  }
  return 0;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) { return sphxr::bench::Main(argc, argv); }
