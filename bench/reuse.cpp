// sphxr_bench_reuse: the trade of activity-based reuse (Huang et al. 2013, section 3.3), measured.
//
// Two scenes: scenes/deep_tank.json (a 36-spacing-deep pool, 51,840 particles, starting hydrostatic,
// with a 1,000-particle block dropped into one corner: 52,840) and scenes/dam_break_1m.json (50,653 particles). Each is run
// with reuse off (the reference) and with every setting of the sweep (delta1, delta2, threshold T,
// IDLE), all from the same initial state, on the CPU backend, to the same simulated time with the
// scenes' fixed time step, so the steps of all runs fall at the same simulated times. Per run:
//   - step_ms: median wall time of Solver::Step over the run (the whole step, every stage);
//   - speedup: the reference's median step time divided by the run's. By default every run is paired
//     with a reference (reuse off) solver stepped in lock-step with it, one step of each in turn
//     (which goes first alternates), so a change of the machine's speed during the run hits both
//     alike: the ratio is measured side by side. --unpaired runs each setting alone and divides the
//     mean of the two reference runs (first and last) instead; the shared VM's speed drifts by 30 %
//     over a sweep, so that ratio is noise. Both reference runs are in the CSV either way;
//   - active: mean over the steps of the fraction of particles that computed density and forces;
//   - mean_density_error: time average of the per-step mean compression, mean of max(0, rho/rho0 - 1);
//     peak_density_error: the largest per-step mean compression in the run;
//   - surface_rms: the free-surface height field against the reference's at fixed simulated times: the
//     height of a column (one spacing square, over x and z) is the highest particle in it whose density
//     is above half the rest density (spray excluded); RMS over the columns that hold water in both runs,
//     in spacings, averaged over the sample times;
//   - front_dev: the surge front (sim::SurgeFront from the tank's back wall) against the reference's,
//     largest relative deviation over the sample times (dam break only);
//   - max_speed, lost/clamped counts, NaN: the run's health;
//   - wall_speedup (paired runs only): the reference's wall time in Solver::Step over the run's simulated
//     time divided by the run's. Where steps get dearer during a run (the dam break's splash) and reuse
//     skips most while they are cheap, the medians' ratio misses that; a run that takes more steps
//     (a time step clamped to a faster flow's CFL limit) pays for them here.
// --csv writes one row per run (bench/results/reuse.csv); bench/plot_reuse.py draws docs/images/reuse.png.
#include <algorithm>
#include <array>
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
#include "sphxr/sim/measure.h"
#include "sphxr/sim/solver.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::bench {
namespace {

struct Setting {
  std::string name;  // "off", a preset name, "sweep" or "custom"
  bool enabled = false;
  float delta1 = 1, delta2 = 1, threshold = 1.2f;
  int idle = 3;
};

struct Args {
  bool quick = false;
  int threads = 0;
  std::string csv;
  std::string only;  // "deep_tank" or "dam_break_1m": one scene only
  double time = 0.0; // 0: the default per scene
  bool unpaired = false;
  bool presetsOnly = false;
  bool help = false;
  std::vector<Setting> custom;  // --setting: these instead of the sweep and the presets
};

const char* kUsage =
    "usage: sphxr_bench_reuse [--quick] [--threads N] [--csv FILE] [--scene deep_tank|dam_break_1m] [--time T]\n"
    "                          [--presets] [--unpaired] [--setting D1,D2,T,IDLE]...\n"
    "  --quick         off, the three presets and 2 more settings, to t = 0.1 s (a smoke run)\n"
    "  --threads N     CPU backend threads (default 0 = all cores)\n"
    "  --csv FILE      write one row per run to FILE (overwritten; only a file with this bench's header)\n"
    "  --scene NAME    one of the two scenes only\n"
    "  --time T        simulated seconds per run (default 0.3 deep_tank, 0.5 dam_break_1m)\n"
    "  --presets       off and the three presets only (no sweep)\n"
    "  --unpaired      no lock-step reference: half the time, but the speed-up is then against reference runs\n"
    "                  made minutes apart (noise on a shared machine)\n"
    "  --setting D1,D2,T,IDLE  run this setting (delta1, delta2, threshold, idle steps) instead of\n"
    "                  the sweep and the presets (also with --presets or --quick); repeatable. Each run is\n"
    "                  named \"custom\"; its parameters are in the row.\n"
    "The printout ends each scene with every stage's mean ms per step for each paired run and its\n"
    "reference, both runs' mean whole step, and the ratio of their wall times over the same simulated\n"
    "time (a scene whose steps get dearer, as the dam break's do, can give another ratio than the\n"
    "medians; a run that takes more steps pays for them) (not with --unpaired, which has no reference\n"
    "to set beside it).\n";

/// "D1,D2,T,IDLE" (--setting) into a reuse-on setting named "custom"; false unless it is four decimal
/// numbers from 0 to 1e9 (as the scene's reuse section allows) that stay what they say as floats (1e-50
/// would become 0), IDLE a whole number to 1000.
bool ParseSetting(const std::string& text, Setting* out) {
  float v[4] = {0, 0, 0, 0};
  const int fields = 4;
  size_t at = 0;
  for (int k = 0; k < fields; ++k) {
    const size_t comma = k < fields - 1 ? text.find(',', at) : text.size();
    if (comma == std::string::npos) return false;
    const std::string field = text.substr(at, comma - at);
    at = comma + 1;
    // Digits, a point and an exponent only: no sign, space, hex, inf or nan.
    if (field.empty() || field.find_first_not_of("0123456789.eE+-") != std::string::npos || field[0] == '+' ||
        field[0] == '-') {
      return false;
    }
    double d = 0.0;
    if (!ParseNumber(field.c_str(), &d) || d > 1e9) return false;
    v[k] = static_cast<float>(d);
    if (d > 0.0 && !(v[k] > 0.0f)) return false;  // a positive number too small for a float
  }
  if (v[3] != std::floor(v[3]) || v[3] > 1000.0f) return false;
  out->name = "custom";
  out->enabled = true;
  out->delta1 = v[0];
  out->delta2 = v[1];
  out->threshold = v[2];
  out->idle = static_cast<int>(v[3]);
  return true;
}

/// Prints the usage to stderr; false, for ParseArgs to return.
bool Usage() {
  std::fputs(kUsage, stderr);
  return false;
}

/// False on bad usage, after printing why: the usage for an unknown option or a missing value, one line
/// for a bad number (the usage would not say which).
bool ParseArgs(int argc, char** argv, Args* out) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&](std::string* v) {
      if (i + 1 >= argc) return false;
      *v = argv[++i];
      return true;
    };
    std::string v;
    if (a == "--quick") {
      out->quick = true;
    } else if (a == "--threads" && next(&v)) {
      if (!IntegerOption("sphxr_bench_reuse", a, v.c_str(), 0, 1024, &out->threads)) return false;
    } else if (a == "--csv" && next(&v)) {
      out->csv = v;
    } else if (a == "--scene" && next(&v)) {
      if (v != "deep_tank" && v != "dam_break_1m") {
        std::fprintf(stderr, "sphxr_bench_reuse: --scene %s: must be deep_tank or dam_break_1m\n", v.c_str());
        return false;
      }
      out->only = v;
    } else if (a == "--time" && next(&v)) {
      if (!ParseNumber(v.c_str(), &out->time) || !(out->time > 0.0)) {
        std::fprintf(stderr, "sphxr_bench_reuse: --time %s: must be a finite number above 0 (s)\n", v.c_str());
        return false;
      }
    } else if (a == "--presets") {
      out->presetsOnly = true;
    } else if (a == "--unpaired") {
      out->unpaired = true;
    } else if (a == "--setting" && next(&v)) {
      Setting setting;
      if (!ParseSetting(v, &setting)) {
        std::fprintf(stderr,
                     "sphxr_bench_reuse: --setting %s: must be D1,D2,T,IDLE,TOL[,HOLD] (numbers from 0, IDLE a "
                     "whole number of steps from 0 to 1000, HOLD 0, 1 or 2)\n",
                     v.c_str());
        return false;
      }
      out->custom.push_back(setting);
    } else if (a == "--help" || a == "-h") {
      out->help = true;
    } else {
      std::fprintf(stderr, "sphxr_bench_reuse: %s: unknown option or missing value\n", a.c_str());
      return Usage();
    }
  }
  return true;
}

Setting Sweep(float d1, float d2, float t, int idle) {
  Setting s;
  s.name = "sweep";
  s.enabled = true;
  s.delta1 = d1;
  s.delta2 = d2;
  s.threshold = t;
  s.idle = idle;
  return s;
}

Setting Preset(const char* name) {
  sim::ReuseParams r;
  sim::ApplyReusePreset(name, &r);
  Setting s = Sweep(r.delta1, r.delta2, r.threshold, r.idle);
  s.name = name;
  return s;
}

/// The sweep: one factor at a time around `balanced` (delta1 0, delta2 1, T 1.5, IDLE 3), then the presets.
std::vector<Setting> Settings(bool quick, bool presetsOnly, const std::vector<Setting>& custom) {
  if (!custom.empty()) return custom;
  std::vector<Setting> s;
  if (quick && !presetsOnly) {
    s = {Sweep(0, 1, 1.5f, 1), Sweep(0, 1, 1.3f, 3)};
  } else if (!presetsOnly) {
    for (int idle : {1, 2, 5}) s.push_back(Sweep(0, 1, 1.5f, idle));
    for (float t : {1.3f, 1.4f, 1.6f, 2.0f}) s.push_back(Sweep(0, 1, t, 3));
    for (float d1 : {0.1f, 0.25f, 0.5f}) s.push_back(Sweep(d1, 1, 1.5f, 3));
    for (float d2 : {0.8f, 1.2f}) s.push_back(Sweep(0, d2, 1.5f, 3));
  }
  for (const char* p : {"accurate", "balanced", "fast"}) s.push_back(Preset(p));
  return s;
}

/// Column heights (one spacing square over x and z): the highest particle with rho > rho0 / 2.
struct HeightField {
  int nx = 0, nz = 0;
  std::vector<float> h;  // NaN: no water
};

HeightField Heights(const sim::HostFluid& f, const sim::SceneSetup& scene) {
  const float dx = scene.params.spacing;
  HeightField hf;
  hf.nx = std::max(1, static_cast<int>(std::ceil((scene.tank.max.x - scene.tank.min.x) / dx)));
  hf.nz = std::max(1, static_cast<int>(std::ceil((scene.tank.max.z - scene.tank.min.z) / dx)));
  hf.h.assign(static_cast<size_t>(hf.nx) * hf.nz, std::nanf(""));
  const float half = 0.5f * scene.params.restDensity;
  for (size_t i = 0; i < f.size(); ++i) {
    if (!(f.density[i] > half)) continue;
    const int cx = std::clamp(static_cast<int>((f.position[i].x - scene.tank.min.x) / dx), 0, hf.nx - 1);
    const int cz = std::clamp(static_cast<int>((f.position[i].z - scene.tank.min.z) / dx), 0, hf.nz - 1);
    float& h = hf.h[static_cast<size_t>(cz) * hf.nx + cx];
    if (std::isnan(h) || f.position[i].y > h) h = f.position[i].y;
  }
  return hf;
}

/// RMS difference of two height fields in spacings, over the columns with water in both.
double HeightRms(const HeightField& a, const HeightField& b, float dx) {
  double sum = 0.0;
  int64_t n = 0;
  for (size_t k = 0; k < a.h.size(); ++k) {
    if (std::isnan(a.h[k]) || std::isnan(b.h[k])) continue;
    const double d = (a.h[k] - b.h[k]) / dx;
    sum += d * d;
    ++n;
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

struct Sample {
  double time;
  HeightField heights;
  float front;
};

constexpr int kStages = static_cast<int>(sim::Stage::kCount);

struct Result {
  Setting setting;
  int fluid = 0;
  int64_t steps = 0;
  double stepMs = 0, active = 0, meanErr = 0, peakErr = 0, maxSpeed = 0;
  int64_t clamped = 0;
  bool finite = true;
  std::vector<Sample> samples;
  double surfaceRms = 0, frontDev = 0;
  double loadStart = 0, loadEnd = 0;
  double pairedRefMs = std::nan("");  // median step of the lock-step reference (NaN: unpaired)
  std::array<double, kStages> stageMs{};          // mean ms per step in each stage (sim::Stage)
  std::array<double, kStages> pairedRefStageMs{};  // the same for the lock-step reference (0: unpaired)
  double meanMs = 0.0;                             // mean ms per step (Totals::stepSeconds)
  double stepSeconds = 0.0;                        // the run's wall time in Solver::Step, to the scene's end time
  double pairedRefMeanMs = std::nan("");           // the same two for the lock-step reference
  double pairedRefStepSeconds = std::nan("");
};

struct SceneCase {
  std::string name;
  std::string path;
  double time;
  std::vector<double> sampleTimes;
  bool dam;
};

/// One solver of a run: created from the scene with the setting's reuse parameters, stepped one step
/// at a time (so that two can run in lock-step), its statistics gathered into a Result.
class Runner {
 public:
  bool Init(const SceneCase& sc, const Setting& setting, int threads, Result* r) {
    m_sc = &sc;
    m_r = r;
    r->setting = setting;
    if (Status s = app::LoadScene(sc.path, &m_scene); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return false;
    }
    m_scene.setup.reuse.enabled = setting.enabled;
    m_scene.setup.reuse.delta1 = setting.delta1;
    m_scene.setup.reuse.delta2 = setting.delta2;
    m_scene.setup.reuse.threshold = setting.threshold;
    m_scene.setup.reuse.idle = setting.idle;
    sim::SolverConfig config;
    config.device = sim::Device::kCpu;
    config.threads = threads;
    if (Status s = sim::Solver::Create(m_scene.setup, config, &m_solver); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return false;
    }
    r->fluid = m_solver->FluidCount();
    m_dx = m_scene.setup.params.spacing;
    m_minPerBin =
        std::max(1, static_cast<int>(0.1f * (m_scene.setup.tank.max.z - m_scene.setup.tank.min.z) / m_dx));
    return true;
  }
  double Time() const { return m_solver->Time(); }
  bool Done() const { return m_solver->Time() >= m_sc->time - 1e-9; }
  /// One step, timed; the statistics and, at the sample times, the surface and front.
  bool Step() {
    const auto t0 = std::chrono::steady_clock::now();
    if (Status s = m_solver->Step(); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return false;
    }
    m_stepMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const sim::StepInfo& info = m_solver->LastStep();
    if (!std::isfinite(info.maxSpeed) || !std::isfinite(info.meanDensityError)) m_r->finite = false;
    m_errSum += info.meanDensityError * info.dt;
    m_errTime += info.dt;
    m_activeSum += info.activeFraction;
    m_r->peakErr = std::max<double>(m_r->peakErr, info.meanDensityError);
    m_r->maxSpeed = std::max<double>(m_r->maxSpeed, info.maxSpeed);
    m_r->clamped += info.clamped;
    if (m_nextSample < m_sc->sampleTimes.size() && m_solver->Time() >= m_sc->sampleTimes[m_nextSample] - 1e-7) {
      m_solver->Download(&m_host);
      Sample smp;
      smp.time = m_solver->Time();
      smp.heights = Heights(m_host, m_scene.setup);
      smp.front = sim::SurgeFront(m_host, m_scene.setup.tank.min.x, m_dx, m_minPerBin);
      m_r->samples.push_back(std::move(smp));
      ++m_nextSample;
    }
    return true;
  }
  void Finish() {
    m_r->steps = static_cast<int64_t>(m_stepMs.size());
    m_r->stepMs = Median(m_stepMs);
    m_r->active = m_stepMs.empty() ? 1.0 : m_activeSum / static_cast<double>(m_stepMs.size());
    m_r->meanErr = m_errTime > 0 ? m_errSum / m_errTime : 0.0;
    const sim::Totals& totals = m_solver->GetTotals();
    for (int k = 0; k < kStages; ++k) {
      m_r->stageMs[k] = totals.steps > 0 ? 1e3 * totals.stageSeconds[k] / static_cast<double>(totals.steps) : 0.0;
    }
    m_r->meanMs = totals.steps > 0 ? 1e3 * totals.stepSeconds / static_cast<double>(totals.steps) : 0.0;
    m_r->stepSeconds = totals.stepSeconds;
  }

 private:
  const SceneCase* m_sc = nullptr;
  Result* m_r = nullptr;
  app::SceneFile m_scene;
  std::unique_ptr<sim::Solver> m_solver;
  float m_dx = 0.0f;
  int m_minPerBin = 1;
  std::vector<double> m_stepMs;
  double m_errTime = 0.0, m_errSum = 0.0, m_activeSum = 0.0;
  size_t m_nextSample = 0;
  sim::HostFluid m_host;
};

/// Runs `setting` to the scene's end time. With `paired`, a reference solver (reuse off) runs in
/// lock-step: one step of each in turn, the one behind in simulated time first (ties alternate), so
/// both see the same machine; its median step time goes to r->pairedRefMs.
bool Run(const SceneCase& sc, const Setting& setting, int threads, bool paired, Result* r) {
  Runner run;
  if (!run.Init(sc, setting, threads, r)) return false;
  Result refResult;
  Runner ref;
  Setting off;
  off.name = "off";
  if (paired && !ref.Init(sc, off, threads, &refResult)) return false;
  r->loadStart = LoadAverage();
  bool refFirst = false;
  while (!run.Done() || (paired && !ref.Done())) {
    if (!paired) {
      if (!run.Step()) return false;
      continue;
    }
    refFirst = !refFirst;
    const bool stepRef = !ref.Done() && (run.Done() || ref.Time() < run.Time() - 1e-9 ||
                                          (std::fabs(ref.Time() - run.Time()) <= 1e-9 && refFirst));
    if (stepRef) {
      if (!ref.Step()) return false;
      if (!run.Done() && !run.Step()) return false;
    } else {
      if (!run.Step()) return false;
      if (!ref.Done() && !ref.Step()) return false;
    }
  }
  r->loadEnd = LoadAverage();
  run.Finish();
  if (paired) {
    ref.Finish();
    r->pairedRefMs = refResult.stepMs;
    r->pairedRefStageMs = refResult.stageMs;
    r->pairedRefMeanMs = refResult.meanMs;
    r->pairedRefStepSeconds = refResult.stepSeconds;
  }
  return true;
}

void Compare(const Result& ref, Result* r, float dx) {
  double rms = 0.0, front = 0.0;
  const size_t n = std::min(ref.samples.size(), r->samples.size());
  for (size_t k = 0; k < n; ++k) {
    rms += HeightRms(ref.samples[k].heights, r->samples[k].heights, dx);
    if (ref.samples[k].front > 0) {
      front = std::max(front, std::fabs(static_cast<double>(r->samples[k].front) / ref.samples[k].front - 1.0));
    }
  }
  r->surfaceRms = n ? rms / static_cast<double>(n) : 0.0;
  r->frontDev = front;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) {
  using namespace sphxr;
  using namespace sphxr::bench;
  Args args;
  if (!ParseArgs(argc, argv, &args)) return 2;
  if (args.help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  SetLogLevel(LogLevel::kWarn);
  if (args.threads > 0) omp_set_num_threads(args.threads);
  std::vector<SceneCase> cases;
  const double quickTime = 0.1;
  if (args.only.empty() || args.only == "deep_tank") {
    const double t = args.quick ? quickTime : (args.time > 0 ? args.time : 0.3);
    cases.push_back({"deep_tank", SPHXR_SCENES_DIR "/deep_tank.json", t, {0.4 * t, 0.7 * t, t}, false});
  }
  if (args.only.empty() || args.only == "dam_break_1m") {
    const double t = args.quick ? quickTime : (args.time > 0 ? args.time : 0.5);
    cases.push_back({"dam_break_1m", SPHXR_SCENES_DIR "/dam_break_1m.json", t, {t / 3, 2 * t / 3, t}, true});
  }
  std::ofstream csv;
  if (const std::string why = args.csv.empty() ? std::string() : OpenCsv(args.csv,
               "timestamp_utc,cpu_model,nproc,threads,scene,fluid,setting,enabled,delta1,delta2,threshold,idle,"
               "sim_time,steps,step_ms,ref_step_ms_first,ref_step_ms_last,paired_ref_step_ms,speedup,active_fraction,"
               "mean_density_error,peak_density_error,surface_rms_spacings,front_deviation,max_speed,clamped,"
               "finite,load_avg_start,load_avg_end,wall_speedup",
               false, &csv);
      !why.empty()) {
    std::fprintf(stderr, "%s\n", why.c_str());
    return 1;
  }
  const std::string when = UtcTimestamp();
  const std::string cpu = CpuModel();
  const int threads = args.threads > 0 ? args.threads : omp_get_max_threads();
  std::printf("# sphxr_bench_reuse on %s, %d cores, %d threads, %s\n", cpu.c_str(), CpuCount(), threads, when.c_str());
  for (const SceneCase& sc : cases) {
    Setting off;
    off.name = "off";
    Result ref, refLast;
    std::fprintf(stderr, "%s: reference (reuse off) to t = %g s ...\n", sc.name.c_str(), sc.time);
    if (!Run(sc, off, args.threads, false, &ref)) return 1;
    std::vector<Result> results;
    for (const Setting& s : Settings(args.quick, args.presetsOnly, args.custom)) {
      std::fprintf(stderr, "%s: %s delta1 %g delta2 %g T %g IDLE %d ...\n", sc.name.c_str(), s.name.c_str(), s.delta1,
                   s.delta2, s.threshold, s.idle);
      Result r;
      if (!Run(sc, s, args.threads, !args.unpaired, &r)) return 1;
      results.push_back(std::move(r));
    }
    std::fprintf(stderr, "%s: reference again (timing drift) ...\n", sc.name.c_str());
    if (!Run(sc, off, args.threads, false, &refLast)) return 1;
    const double refMs = 0.5 * (ref.stepMs + refLast.stepMs);
    app::SceneFile scene;
    if (Status s = app::LoadScene(sc.path, &scene); !s) return 1;
    const float dx = scene.setup.params.spacing;
    std::printf("\n## %s: %d particles, %.2f s simulated, reference %.2f / %.2f ms per step (first / last run)\n",
                sc.name.c_str(), ref.fluid, sc.time, ref.stepMs, refLast.stepMs);
    std::printf("%s\n", args.unpaired ? "speed-up against the mean of the two reference runs"
                                       : "speed-up against a reference stepped in lock-step with each run (ref_ms)");
    std::printf("%-9s %6s %6s %6s %5s %8s %8s %7s %7s %9s %9s %8s %8s %6s\n", "setting", "delta1", "delta2", "T", "IDLE",
                "step_ms", "ref_ms", "speedup", "active", "mean_err%", "peak_err%", "surf_rms", "front%", "vmax");
    results.insert(results.begin(), ref);
    for (Result& r : results) {
      Compare(ref, &r, dx);
      const bool paired = std::isfinite(r.pairedRefMs);
      const double speedup = r.stepMs > 0 ? (paired ? r.pairedRefMs : refMs) / r.stepMs : 0.0;
      std::printf("%-9s %6.2f %6.2f %6.2f %5d %8.2f %8.2f %7.2f %7.3f %9.3f %9.3f %8.3f %8.2f %6.2f%s\n",
                  r.setting.name.c_str(), r.setting.delta1, r.setting.delta2, r.setting.threshold, r.setting.idle,
                  r.stepMs, paired ? r.pairedRefMs : refMs, speedup, r.active, 100 * r.meanErr, 100 * r.peakErr, r.surfaceRms, 100 * r.frontDev,
                  r.maxSpeed, r.finite ? "" : "  NaN!");
      if (csv) {
        csv << when << ',' << CsvField(cpu) << ',' << CpuCount() << ',' << threads << ',' << sc.name << ',' << r.fluid
            << ',' << r.setting.name << ',' << (r.setting.enabled ? 1 : 0) << ',' << r.setting.delta1 << ','
            << r.setting.delta2 << ',' << r.setting.threshold << ',' << r.setting.idle << ','
            << sc.time << ','
            << r.steps << ',' << r.stepMs << ',' << ref.stepMs << ',' << refLast.stepMs << ',' << r.pairedRefMs << ','
            << speedup << ','
            << r.active << ',' << r.meanErr << ',' << r.peakErr << ',' << r.surfaceRms << ','
            << (sc.dam ? r.frontDev : std::nan("")) << ',' << r.maxSpeed << ',' << r.clamped << ','
            << (r.finite ? 1 : 0) << ',' << r.loadStart << ',' << r.loadEnd << ','
            << (paired ? r.pairedRefStepSeconds / r.stepSeconds : std::nan("")) << '\n';
      }
    }
    // Where the time goes: each stage's mean per step, the run against its lock-step reference.
    if (!args.unpaired) {
      std::printf("stages, mean ms per step: the run (reference in lock-step)\n%-9s %6s %6s %6s %5s", "setting",
                  "delta1", "delta2", "T", "IDLE");
      for (int k = 0; k < kStages; ++k) std::printf(" %15s", sim::StageName(static_cast<sim::Stage>(k)));
      std::printf(" %17s %12s\n", "mean step", "wall speedup");
      for (const Result& r : results) {
        if (!std::isfinite(r.pairedRefMs)) continue;
        std::printf("%-9s %6.2f %6.2f %6.2f %5d", r.setting.name.c_str(), r.setting.delta1, r.setting.delta2,
                    r.setting.threshold, r.setting.idle);
        for (int k = 0; k < kStages; ++k) std::printf(" %6.3f (%6.3f)", r.stageMs[k], r.pairedRefStageMs[k]);
        std::printf(" %7.3f (%7.3f) %12.3f\n", r.meanMs, r.pairedRefMeanMs, r.pairedRefStepSeconds / r.stepSeconds);
      }
    }
    std::fflush(stdout);
  }
  return 0;
}
