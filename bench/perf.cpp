// sphxr_bench_perf: speed and memory of the CPU backend on scenes/dam_break_1m.json (a 1 m cube of
// water collapsing in a 4 x 3 x 1.5 m tank, fixed dt 0.5 ms), at 50,653 and 205,379 fluid particles.
//
// Per configuration: warm-up steps, then measured steps, each timed around Solver::Step; the median
// step time; the per-stage split (Solver::GetTotals().stageSeconds over the measured window); the
// neighbour interactions per second (pairs within the support radius counted by brute force on a host
// copy, x2 for the density and force passes); the mean density error at the end; the peak memory per
// particle (growth of the process's peak RSS, VmHWM) next to the solver's own estimate
// (sim::EstimateMemoryBytes). Prints a markdown table; --csv appends one row per configuration.
//
// The benchmark reports; it never fails on a target (speed and memory are not asserted anywhere).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <omp.h>

#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/host_grid.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::bench {
namespace {

using sim::Vec3;
using sim::Vec4;

// The targets, reported next to the numbers (never asserted).
constexpr double kTargetMsPerStep50k = 17.0;      // on the 2-core reference machine
constexpr double kReferenceLibraryMs50k = 68.0;   // a widely used CPU SPH library, same scene, same machine
constexpr double kTargetBytesPerParticle = 250.0;
// Above this 1-minute load average before a run, other work shares the cores and the timings say so.
constexpr double kBusyLoad = 0.5;

struct Args {
  bool quick = false;
  int threads = 0;  // 0 = all cores
  sim::Device device = sim::Device::kCpu;
  std::string csv;
  std::string scene = SPHXR_SCENES_DIR "/dam_break_1m.json";
  std::vector<float> spacings;  // empty: the defaults
  int warmup = -1, measured = -1;  // -1: the defaults of the mode
  bool help = false;
};

const char* kUsage =
    "usage: sphxr_bench_perf [--quick] [--threads N] [--device D] [--csv FILE] [--scene FILE] [--spacing H]...\n"
    "                        [--warmup N] [--measured N]\n"
    "  --device D    cpu (default), cuda or cpu-reference (scripts/gpu_check.sh times cuda)\n"
    "  --quick       20 warm-up + 20 measured steps, 50k particles only (a smoke run)\n"
    "  --threads N   CPU backend threads (default 0 = all cores)\n"
    "  --csv FILE    append one row per configuration to FILE (header written when the file is new)\n"
    "  --scene FILE  scene (default " SPHXR_SCENES_DIR "/dam_break_1m.json)\n"
    "  --spacing H   run this spacing in m instead of the defaults 0.026316 (50,653 fluid particles) and\n"
    "                0.016949 (205,379); repeatable\n"
    "  --warmup N, --measured N   step counts (defaults 100 and 200; 20 and 20 with --quick)\n";

bool ParseArgs(int argc, char** argv, Args* out) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&](const char** v) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: missing value\n%s", a.c_str(), kUsage);
        return false;
      }
      *v = argv[++i];
      return true;
    };
    const char* v = nullptr;
    if (a == "--quick") {
      out->quick = true;
    } else if (a == "--threads") {
      if (!next(&v)) return false;
      if (!IntegerOption("sphxr_bench_perf", a, v, 0, 1024, &out->threads)) return false;
    } else if (a == "--device") {
      if (!next(&v)) return false;
      if (!sim::ParseDevice(v, &out->device) || out->device == sim::Device::kAuto) {
        std::fprintf(stderr, "sphxr_bench_perf: --device %s: must be cpu, cuda or cpu-reference\n", v);
        return false;
      }
    } else if (a == "--csv") {
      if (!next(&v)) return false;
      out->csv = v;
    } else if (a == "--scene") {
      if (!next(&v)) return false;
      out->scene = v;
    } else if (a == "--spacing") {
      if (!next(&v)) return false;
      double h = 0.0;
      if (!ParseNumber(v, &h) || !(h > 0.0 && h < 1.0)) {
        std::fprintf(stderr, "sphxr_bench_perf: --spacing %s: must be a number between 0 and 1 (m)\n", v);
        return false;
      }
      out->spacings.push_back(static_cast<float>(h));
    } else if (a == "--warmup" || a == "--measured") {
      if (!next(&v)) return false;
      const bool warmup = a == "--warmup";
      if (!IntegerOption("sphxr_bench_perf", a, v, warmup ? 0 : 1, 1000000, warmup ? &out->warmup : &out->measured))
        return false;
    } else if (a == "--help" || a == "-h") {
      out->help = true;
    } else {
      std::fprintf(stderr, "unknown argument '%s'\n%s", a.c_str(), kUsage);
      return false;
    }
  }
  return true;
}

// ---- brute-force neighbour pairs on the host (sim/host_grid.h) ----------------------------------

struct PairCount {
  int64_t fluidFluid = 0;     // ordered pairs (i, j), i != j, both fluid, |x_i - x_j| < H
  int64_t fluidBoundary = 0;  // (i, b), i fluid, b boundary, |x_i - x_b| < H
  int64_t Total() const { return fluidFluid + fluidBoundary; }
};

/// Every fluid particle's neighbours within the support radius H, counted as the solver's per-particle
/// loops see them: each fluid-fluid pair once from each side (ordered pairs), self excluded.
PairCount CountPairs(const sim::HostFluid& fluid, const sim::HostBoundary& boundary, float support) {
  PairCount out;
  if (fluid.size() == 0) return out;
  Vec3 lo, hi;
  sim::BoundingBox({&fluid.position, &boundary.position}, &lo, &hi);
  const sim::HostGrid fluidGrid(fluid.position, lo, hi, support);
  const sim::HostGrid boundaryGrid(boundary.position, lo, hi, support);
  const float h2 = support * support;  // the solver compares r^2 < H^2 in float, as here
  for (size_t i = 0; i < fluid.size(); ++i) {
    const Vec4 xi = fluid.position[i];
    auto within = [&](const Vec4& xj) {
      const float dx = xi.x - xj.x, dy = xi.y - xj.y, dz = xi.z - xj.z;
      return dx * dx + dy * dy + dz * dz < h2;
    };
    fluidGrid.ForEachNear(Xyz(xi), [&](uint32_t j) {
      if (j != i && within(fluid.position[j])) ++out.fluidFluid;
    });
    boundaryGrid.ForEachNear(Xyz(xi), [&](uint32_t b) {
      if (within(boundary.position[b])) ++out.fluidBoundary;
    });
  }
  return out;
}

PairCount CountSolverPairs(const sim::Solver& solver) {
  sim::HostFluid fluid;
  sim::HostBoundary boundary;
  solver.Download(&fluid);
  solver.DownloadBoundary(&boundary);
  return CountPairs(fluid, boundary, solver.SupportRadius());
}

// ---- one configuration ---------------------------------------------------------------------------

constexpr int kStages = static_cast<int>(sim::Stage::kCount);

struct Result {
  float spacing = 0.0f;
  int fluid = 0, boundary = 0;
  int threads = 0;
  int warmup = 0, measured = 0;
  double meanDt = 0.0;          // s, mean step over the measured window
  int64_t dtClampedSteps = 0;   // measured steps where fixed_dt was above the stability limit
  double medianMs = 0.0, meanMs = 0.0, p10Ms = 0.0, p90Ms = 0.0, minMs = 0.0, maxMs = 0.0;
  double stageMs[kStages] = {};
  double cpuMsPerStep = 0.0;    // process CPU time (all threads) per measured step
  PairCount pairsStart, pairsEnd;
  double pairsPerStep = 0.0;        // mean of start and end counts
  double interactionsPerSecond = 0.0;
  float meanDensityError = 0.0f;    // of the last step
  float maxDensityError = 0.0f;     // of the last step
  int64_t rssBase = -1, rssPeak = -1;  // bytes (VmHWM)
  bool rssResetOk = false;
  double rssBytesPerParticle = -1.0;
  double estimateBytesPerParticle = 0.0;
  double wallSecondsTotal = 0.0;    // creation + warm-up + measured, for the log
};

bool RunConfiguration(const Args& args, float spacing, int warmup, int measured, Result* r) {
  r->spacing = spacing;
  r->warmup = warmup;
  r->measured = measured;
  app::SceneFile scene;
  if (Status s = app::LoadScene(args.scene, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  if (Status s = app::SetSolverParam(&scene.setup, Format("spacing=%.9g", spacing)); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  const sim::ParticleCounts counts = sim::CountParticles(scene.setup);
  const double particles = static_cast<double>(counts.fluid + counts.boundary);
  r->estimateBytesPerParticle = static_cast<double>(sim::EstimateMemoryBytes(counts)) / particles;

  // Peak RSS growth: the baseline is taken after returning freed memory and resetting the peak, so a
  // previous configuration's peak does not hide this one's.
  r->rssResetOk = ResetPeakRss();
  r->rssBase = ProcStatusBytes("VmHWM");
  const auto begin = std::chrono::steady_clock::now();

  sim::SolverConfig config;
  config.device = args.device;
  config.threads = args.threads;
  std::unique_ptr<sim::Solver> solver;
  if (Status s = sim::Solver::Create(scene.setup, config, &solver); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  r->fluid = solver->FluidCount();
  r->boundary = solver->BoundaryCount();
  r->threads = omp_get_max_threads();
  std::fprintf(stderr, "spacing %.6g m: %d fluid + %d boundary particles, %d threads; %d warm-up steps ...\n", spacing,
               r->fluid, r->boundary, r->threads, warmup);

  auto step = [&]() -> bool {
    if (Status s = solver->Step(); !s) {
      std::fprintf(stderr, "step failed: %s\n", s.message().c_str());
      return false;
    }
    if (!std::isfinite(solver->LastStep().maxSpeed)) {
      std::fprintf(stderr, "the simulation became non-finite at t = %g s\n", solver->Time());
      return false;
    }
    return true;
  };
  for (int i = 0; i < warmup; ++i) {
    if (!step()) return false;
  }
  // The peak so far covers creation (with its host copy) and steady steps (sort temporaries included).
  const int64_t peakWarm = ProcStatusBytes("VmHWM");

  // Pair count at the start of the measured window; its host copies are freed and the peak reset
  // again, so they do not count as solver memory.
  r->pairsStart = CountSolverPairs(*solver);
  const bool resetAgain = ResetPeakRss();

  std::fprintf(stderr, "  %d measured steps ...\n", measured);
  const sim::Totals before = solver->GetTotals();
  const double timeBefore = solver->Time();
  std::vector<double> ms;
  ms.reserve(measured);
  const double cpuBefore = ProcessCpuSeconds();
  for (int i = 0; i < measured; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!step()) return false;
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  r->cpuMsPerStep = 1e3 * (ProcessCpuSeconds() - cpuBefore) / measured;
  const int64_t peakRun = ProcStatusBytes("VmHWM");
  const sim::Totals after = solver->GetTotals();

  r->medianMs = Median(ms);
  double sum = 0.0;
  for (double v : ms) sum += v;
  r->meanMs = sum / static_cast<double>(ms.size());
  r->p10Ms = Quantile(ms, 0.1);
  r->p90Ms = Quantile(ms, 0.9);
  r->minMs = Quantile(ms, 0.0);
  r->maxMs = Quantile(ms, 1.0);
  for (int s = 0; s < kStages; ++s) r->stageMs[s] = 1e3 * (after.stageSeconds[s] - before.stageSeconds[s]) / measured;
  r->meanDt = (solver->Time() - timeBefore) / measured;
  r->dtClampedSteps = after.dtClampedSteps - before.dtClampedSteps;
  r->meanDensityError = solver->LastStep().meanDensityError;
  r->maxDensityError = solver->LastStep().maxDensityError;

  if (r->rssBase >= 0 && peakWarm >= 0 && r->rssResetOk) {
    r->rssPeak = resetAgain && peakRun >= 0 ? std::max(peakWarm, peakRun) : peakWarm;
    r->rssBytesPerParticle = static_cast<double>(r->rssPeak - r->rssBase) / (r->fluid + r->boundary);
  }

  r->pairsEnd = CountSolverPairs(*solver);
  r->pairsPerStep = 0.5 * static_cast<double>(r->pairsStart.Total() + r->pairsEnd.Total());
  r->interactionsPerSecond = r->medianMs > 0 ? 2.0 * r->pairsPerStep / (1e-3 * r->medianMs) : 0.0;
  r->wallSecondsTotal = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return true;
}

std::string Thousands(int64_t v) {
  const std::string digits = std::to_string(v < 0 ? -v : v);
  std::string out = v < 0 ? "-" : "";
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) {
  using namespace sphxr;
  using namespace sphxr::bench;
  Args args;
  if (!ParseArgs(argc, argv, &args)) return 2;
  if (args.help) {
    std::printf("%s", kUsage);
    return 0;
  }
  SetLogLevel(LogLevel::kWarn);
  // The CSV is opened (and its header checked) before minutes of measuring.
  std::ofstream csv;
  if (!args.csv.empty()) {
    // One column per stage, named as the solver names them (sim::StageName), in the order written below.
    std::string header =
        "timestamp_utc,cpu_model,nproc,threads,load_avg_start,load_avg_end,mode,spacing_m,fluid,boundary,warmup_steps,"
        "measured_steps,dt_ms,dt_clamped_steps,median_ms,mean_ms,p10_ms,p90_ms,min_ms,max_ms";
    for (int s = 0; s < kStages; ++s) header += std::string(",") + sim::StageName(static_cast<sim::Stage>(s)) + "_ms";
    header +=
        ",cpu_ms_per_step,pairs_fluid_fluid,pairs_fluid_boundary,pairs_per_step,interactions_per_s,"
        "mean_density_error,max_density_error,rss_growth_bytes,rss_bytes_per_particle,estimate_bytes_per_particle";
    if (const std::string why = OpenCsv(args.csv, header, /*append=*/true, &csv); !why.empty()) {
      std::fprintf(stderr, "%s\n", why.c_str());
      return 1;
    }
  }

  const std::string model = CpuModel();
  const int cpus = CpuCount();
  const double loadStart = LoadAverage();
  const std::string when = UtcTimestamp();
  const int warmup = args.warmup >= 0 ? args.warmup : (args.quick ? 20 : 100);
  const int measured = args.measured > 0 ? args.measured : (args.quick ? 20 : 200);
  std::vector<float> spacings = args.spacings;
  if (spacings.empty()) {
    spacings.push_back(0.026316f);
    if (!args.quick) spacings.push_back(0.016949f);
  }
  const bool custom = !args.spacings.empty() || args.warmup >= 0 || args.measured > 0;

  std::vector<Result> results;
  for (float h : spacings) {
    Result r;
    if (!RunConfiguration(args, h, warmup, measured, &r)) return 1;
    results.push_back(r);
  }
  const double loadEnd = LoadAverage();

  std::printf("\n## sphxr_bench_perf%s\n\n", args.quick ? " (--quick: a smoke run, not a measurement)"
                                            : custom ? " (custom configuration)" : "");
  std::printf("- scene: %s, CPU backend, fixed dt from the scene (clamped to the stability limit when above it)\n",
              args.scene.c_str());
  std::printf("- machine: %s, nproc %d, solver threads %d; 1-min load average %.2f at start, %.2f at end\n", model.c_str(),
              cpus, results.empty() ? 0 : results[0].threads, loadStart, loadEnd);
  std::printf("- %d warm-up + %d measured steps per configuration; %s\n", warmup, measured, when.c_str());
  if (loadStart > kBusyLoad) {
    std::printf("- **the machine was busy (load average %.2f before the run): these timings are not representative**\n",
                loadStart);
  }
  std::printf("\n");

  std::printf("| fluid | boundary | median ms/step | p10-p90 ms | CPU ms/step | interactions/s | neighbours per fluid particle | "
              "mean density error (end) | peak RSS B/particle | estimate B/particle |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Result& r : results) {
    char rss[32];
    if (r.rssBytesPerParticle >= 0) std::snprintf(rss, sizeof(rss), "%.0f", r.rssBytesPerParticle);
    else std::snprintf(rss, sizeof(rss), "n/a");
    std::printf("| %s | %s | %.2f | %.2f-%.2f | %.2f | %.3g | %.1f | %.3f %% | %s | %.0f |\n", Thousands(r.fluid).c_str(),
                Thousands(r.boundary).c_str(), r.medianMs, r.p10Ms, r.p90Ms, r.cpuMsPerStep, r.interactionsPerSecond,
                r.pairsPerStep / r.fluid, 100.0 * r.meanDensityError, rss, r.estimateBytesPerParticle);
  }
  std::printf("\nPer-stage ms per step (mean over the measured window):\n\n| fluid |");
  for (int s = 0; s < kStages; ++s) std::printf(" %s |", sim::StageName(static_cast<sim::Stage>(s)));
  std::printf(" sum |\n|---:|");
  for (int s = 0; s < kStages; ++s) std::printf("---:|");
  std::printf("---:|\n");
  for (const Result& r : results) {
    double total = 0.0;
    std::printf("| %s |", Thousands(r.fluid).c_str());
    for (int s = 0; s < kStages; ++s) {
      std::printf(" %.2f (%.0f %%) |", r.stageMs[s], r.meanMs > 0 ? 100.0 * r.stageMs[s] / r.meanMs : 0.0);
      total += r.stageMs[s];
    }
    std::printf(" %.2f |\n", total);
  }
  std::printf("\n");
  for (const Result& r : results) {
    std::printf("- %s fluid: mean step %.2f ms (min %.2f, max %.2f), dt %.3g ms%s; pairs per step %s at the start, %s at "
                "the end of the window (fluid-fluid %s, fluid-boundary %s at the start)\n",
                Thousands(r.fluid).c_str(), r.meanMs, r.minMs, r.maxMs, 1e3 * r.meanDt,
                r.dtClampedSteps > 0 ? Format(" (fixed dt clamped to the stability limit in %lld of %d steps)",
                                              static_cast<long long>(r.dtClampedSteps), r.measured)
                                           .c_str()
                                     : "",
                Thousands(r.pairsStart.Total()).c_str(), Thousands(r.pairsEnd.Total()).c_str(),
                Thousands(r.pairsStart.fluidFluid).c_str(), Thousands(r.pairsStart.fluidBoundary).c_str());
    if (r.rssBytesPerParticle >= 0) {
      std::printf("  peak RSS growth %.1f MiB = %.0f B per particle (fluid + boundary), %.0f B per fluid particle\n",
                  static_cast<double>(r.rssPeak - r.rssBase) / 1048576.0, r.rssBytesPerParticle,
                  static_cast<double>(r.rssPeak - r.rssBase) / r.fluid);
    } else {
      std::printf("  (peak RSS could not be reset: memory per particle not reported)\n");
    }
  }
  for (const Result& r : results) {
    if (r.fluid > 60000) continue;
    std::printf("\nTargets (reported, not asserted), %s fluid particles:\n", Thousands(r.fluid).c_str());
    std::printf("- step time <= %.0f ms on a 2-core machine (a widely used CPU SPH library: %.0f ms here): %.2f ms, %s\n",
                kTargetMsPerStep50k, kReferenceLibraryMs50k, r.medianMs,
                r.medianMs <= kTargetMsPerStep50k ? "met" : "NOT met");
    if (r.rssBytesPerParticle >= 0) {
      std::printf("- memory <= %.0f bytes per particle: %.0f (peak RSS growth), %.0f (estimate), %s\n",
                  kTargetBytesPerParticle, r.rssBytesPerParticle, r.estimateBytesPerParticle,
                  r.rssBytesPerParticle <= kTargetBytesPerParticle ? "met" : "NOT met");
    }
  }

  if (csv.is_open()) {
    csv.precision(9);
    for (const Result& r : results) {
      csv << when << ',' << CsvField(model) << ',' << cpus << ',' << r.threads << ',' << loadStart << ',' << loadEnd << ','
          << (args.quick ? "quick" : custom ? "custom" : "full") << ',' << r.spacing << ',' << r.fluid << ',' << r.boundary << ',' << r.warmup
          << ',' << r.measured << ',' << 1e3 * r.meanDt << ',' << r.dtClampedSteps << ',' << r.medianMs << ','
          << r.meanMs << ',' << r.p10Ms << ',' << r.p90Ms << ',' << r.minMs << ',' << r.maxMs;
      for (int s = 0; s < kStages; ++s) csv << ',' << r.stageMs[s];
      csv << ',' << r.cpuMsPerStep;
      csv << ',' << r.pairsStart.fluidFluid << ',' << r.pairsStart.fluidBoundary << ',' << r.pairsPerStep << ','
          << r.interactionsPerSecond << ',' << r.meanDensityError << ',' << r.maxDensityError << ','
          << (r.rssPeak >= 0 ? r.rssPeak - r.rssBase : -1) << ',' << r.rssBytesPerParticle << ','
          << r.estimateBytesPerParticle << '\n';
    }
    std::printf("\nappended %zu row(s) to %s\n", results.size(), args.csv.c_str());
  }
  return 0;
}
