// sphxr_bench_tradeoff: cost against accuracy on the Martin & Moyce (1952) dam break
// (scenes/dam_break.json), swept over particle spacing (a/14, a/20, a/26 with a = 0.05715 m) and, per
// method, the knob that buys accuracy with time (kKnobs): WCSPH's Tait stiffness (x0.5, x1, x4 of the
// scene's value), DFSPH's density tolerance (1 %, 0.1 %, 0.01 %) and PBF's iterations per substep (2, 3,
// 6; its 3 substeps a 90 Hz frame). Everything else is the scene's: the column and the tank are fixed
// in metres, so the particle count changes with the spacing.
//
// Each run goes to t = 0.235 s (tau = t sqrt(g/a) = 3.05) and records:
//   - wall seconds per simulated second (time inside Solver::Step only; the probe is not counted),
//   - the judgement of tests/validation/dam_break_test.cpp against tests/data/martin_moyce_1952.csv
//     (sim::JudgeMartinMoyce: one gate lag for the front and the column height, then the relative
//     error of Z over the measured points with 1.0 <= T <= 3.3; sim::SurgeFront and sim::ColumnHeight on
//     a host copy every step, minPerBin from app::DamBreakMinPerBin, as the headless runner): the lag,
//     RMS, maximum and mean of Z_sim / Z_measured - 1, the height's largest deviation,
//   - the mean density error, time-averaged (weighted by dt) over the run,
//   - the mean iterations of DFSPH's density and divergence solves, PBF's iterations a step.
// --csv writes one row per run (bench/results/tradeoff.csv); bench/plot_tradeoff.py draws docs/images/tradeoff.png.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <omp.h>

#include "bench_util.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/measure.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/solver_table.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif
#ifndef SPHXR_TEST_DATA_DIR
#define SPHXR_TEST_DATA_DIR "tests/data"
#endif

namespace sphxr::bench {
namespace {

struct Args {
  bool quick = false;
  std::string methods = "wcsph,dfsph,pbf";
  int threads = 0;
  std::string csv;
  std::string scene = SPHXR_SCENES_DIR "/dam_break.json";
  std::string measurements = SPHXR_TEST_DATA_DIR "/martin_moyce_1952.csv";
  bool help = false;
};

const char* kUsage =
    "usage: sphxr_bench_tradeoff [--quick] [--methods LIST] [--threads N] [--csv FILE] [--scene FILE] [--data FILE]\n"
    "  --quick       2 configurations per method (a/14 and a/20; stiffness x1, tolerance 0.1 %, 3 iterations) to\n"
    "                t = 0.05 s (a smoke run; the front error then covers only the measured points with T <= 0.93)\n"
    "  --methods L   comma-separated: wcsph, dfsph, pbf (default all three)\n"
    "  --threads N   CPU backend threads (default 0 = all cores)\n"
    "  --csv FILE    write one row per run to FILE (overwritten; only a file with this bench's header)\n"
    "  --scene FILE  dam-break scene (default " SPHXR_SCENES_DIR "/dam_break.json)\n"
    "  --data FILE   Martin & Moyce measurements (default " SPHXR_TEST_DATA_DIR "/martin_moyce_1952.csv)\n";

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
    } else if (a == "--methods") {
      if (!next(&v)) return false;
      out->methods = v;
      std::stringstream ss(out->methods);
      for (std::string m; std::getline(ss, m, ',');) {
        sim::SolverMethod parsed;
        if (!sim::ParseSolverMethod(m, &parsed)) {
          std::fprintf(stderr, "--methods: unknown method '%s' (%s)\n", m.c_str(), sim::SolverNames().c_str());
          return false;
        }
      }
    } else if (a == "--threads") {
      if (!next(&v)) return false;
      if (!IntegerOption("sphxr_bench_tradeoff", a, v, 0, 1024, &out->threads)) return false;
    } else if (a == "--csv") {
      if (!next(&v)) return false;
      out->csv = v;
    } else if (a == "--scene") {
      if (!next(&v)) return false;
      out->scene = v;
    } else if (a == "--data") {
      if (!next(&v)) return false;
      out->measurements = v;
    } else if (a == "--help" || a == "-h") {
      out->help = true;
    } else {
      std::fprintf(stderr, "unknown argument '%s'\n%s", a.c_str(), kUsage);
      return false;
    }
  }
  return true;
}

struct Config {
  sim::SolverMethod method;
  int spacingDivisor;     // spacing = a / divisor
  double knob;            // its method's Knob: WCSPH x the scene's stiffness, DFSPH the tolerance %, PBF iterations
};

/// Per method, the setting that buys accuracy with time, and its sweep.
struct Knob {
  sim::SolverMethod method;
  const char* label;           // for the table and the log
  std::vector<double> values;  // the full sweep
  double quick;                // the smoke run's
};
const Knob kKnobs[] = {
    {sim::SolverMethod::kWcsph, "stiffness x", {0.5, 1.0, 4.0}, 1.0},
    {sim::SolverMethod::kDfsph, "density tolerance %", {1.0, 0.1, 0.01}, 0.1},
    {sim::SolverMethod::kPbf, "iterations", {2.0, 3.0, 6.0}, 3.0},
};

const Knob& KnobOf(sim::SolverMethod m) {
  for (const Knob& k : kKnobs) {
    if (k.method == m) return k;
  }
  std::fprintf(stderr, "sphxr_bench_tradeoff: no sweep for method %s\n", sim::SolverMethodName(m));
  std::exit(2);
}

/// The --set assignment of a configuration's knob (stiffness in Pa from the scene's).
std::string KnobSetting(const Config& c, float sceneStiffness) {
  switch (c.method) {
    case sim::SolverMethod::kWcsph: return Format("stiffness=%.9g", static_cast<float>(c.knob * sceneStiffness));
    case sim::SolverMethod::kDfsph: return Format("density_tolerance=%.9g", c.knob);
    case sim::SolverMethod::kPbf: return Format("pbf_iterations=%.9g", c.knob);
  }
  return std::string();
}

struct Result {
  Config config{};
  float spacing = 0.0f;
  float stiffness = 0.0f;
  float soundSpeed = 0.0f;
  sim::SolverParams params;      // as run (the scene's, with spacing and stiffness overridden)
  std::string friction;          // the scene's tank.friction of the floor
  int fluid = 0, boundary = 0, threads = 0;
  int64_t steps = 0, dtClampedSteps = 0, clampedEvents = 0;
  double simTime = 0.0;
  double stepWall = 0.0;       // s inside Solver::Step
  double loopWall = 0.0;       // s of the whole loop, probe included
  double wallPerSimSecond = 0.0;
  double frontRms = NAN, frontMax = NAN;  // relative
  double frontBias = NAN;                 // mean signed relative error (> 0: the simulated front is ahead)
  int frontPoints = 0;
  double densityIterations = 0.0, divergenceIterations = 0.0;  // DFSPH: means per step
  double frontTMin = 0.0, frontTMax = 0.0;
  double gateLag = NAN;    // s, sim::JudgeMartinMoyce's
  double heightMax = NAN;  // relative, the column height's largest deviation
  double finalZ = 0.0;
  double meanDensityError = 0.0;     // time average
  float peakMeanDensityError = 0.0f;
};

bool Run(const Args& args, const Config& config, double tEnd, double tMin, double tMax,
         const std::vector<sim::DamBreakPoint>& measuredFront, const std::vector<sim::DamBreakPoint>& measuredHeight,
         Result* r) {
  r->config = config;
  app::SceneFile scene;
  if (Status s = app::LoadScene(args.scene, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  if (!scene.damBreak) {
    std::fprintf(stderr, "%s: no probe.dam_break_column_width: not a dam-break scene\n", args.scene.c_str());
    return false;
  }
  const app::DamBreakProbe probe = *scene.damBreak;
  const double a = probe.columnWidth;
  // Only the method, the spacing and the method's knob are overridden, through the same path as --set on
  // the command line.
  const std::string knob = KnobSetting(config, scene.setup.params.stiffness);
  for (const std::string& set : {Format("method=%s", sim::SolverMethodName(config.method)),
                                 Format("spacing=%.9g", a / config.spacingDivisor), knob}) {
    if (Status s = app::SetSolverParam(&scene.setup, set); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return false;
    }
  }
  const float dx = scene.setup.params.spacing;
  r->spacing = dx;
  r->params = scene.setup.params;
  r->friction = sim::WallFrictionName(scene.setup.friction.floor);
  r->stiffness = scene.setup.params.stiffness;
  const int minPerBin = app::DamBreakMinPerBin(probe, dx);
  const double g = std::sqrt(scene.setup.gravity.x * scene.setup.gravity.x + scene.setup.gravity.y * scene.setup.gravity.y +
                             scene.setup.gravity.z * scene.setup.gravity.z);

  sim::SolverConfig solverConfig;
  solverConfig.device = sim::Device::kCpu;
  solverConfig.threads = args.threads;
  std::unique_ptr<sim::Solver> solver;
  if (Status s = sim::Solver::Create(scene.setup, solverConfig, &solver); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return false;
  }
  r->fluid = solver->FluidCount();
  r->boundary = solver->BoundaryCount();
  r->soundSpeed = solver->SoundSpeed();
  r->threads = omp_get_max_threads();
  std::fprintf(stderr, "%s a/%d (%.4g mm), %s %g: %d fluid + %d boundary particles, to t = %g s ...\n",
               sim::SolverMethodName(config.method), config.spacingDivisor, 1e3 * dx,
               KnobOf(config.method).label, config.knob, r->fluid, r->boundary, tEnd);

  sim::HostFluid host;
  std::vector<sim::DamBreakSample> samples;
  auto sample = [&](double t) {
    samples.push_back({t, sim::SurgeFront(host, probe.wallX, dx, minPerBin) / a,
                       sim::ColumnHeight(host, probe.floorY, probe.wallX, dx, std::max(1, minPerBin / 2)) / (2.0 * a)});
  };
  solver->Download(&host);
  sample(0.0);
  double errorTime = 0.0;
  const auto begin = std::chrono::steady_clock::now();
  while (solver->Time() < tEnd - 1e-9) {
    if (Status s = solver->Step(); !s) {
      std::fprintf(stderr, "step failed: %s\n", s.message().c_str());
      return false;
    }
    const sim::StepInfo& info = solver->LastStep();
    if (!std::isfinite(info.maxSpeed)) {
      std::fprintf(stderr, "the simulation became non-finite at t = %g s\n", info.time);
      return false;
    }
    errorTime += static_cast<double>(info.meanDensityError) * info.dt;
    r->peakMeanDensityError = std::max(r->peakMeanDensityError, info.meanDensityError);
    solver->Download(&host);
    sample(info.time);
  }
  r->loopWall = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  const sim::Totals& totals = solver->GetTotals();
  r->steps = totals.steps;
  r->dtClampedSteps = totals.dtClampedSteps;
  r->clampedEvents = totals.clampedEvents;
  r->simTime = solver->Time();
  r->stepWall = totals.stepSeconds;
  r->wallPerSimSecond = r->simTime > 0 ? r->stepWall / r->simTime : 0.0;
  r->meanDensityError = r->simTime > 0 ? errorTime / r->simTime : 0.0;
  r->finalZ = samples.back().front;
  if (totals.steps > 0) {
    r->densityIterations = static_cast<double>(totals.densityIterations) / static_cast<double>(totals.steps);
    r->divergenceIterations = static_cast<double>(totals.divergenceIterations) / static_cast<double>(totals.steps);
  }

  // The shared judge (sim/measure.h): one gate lag for both series, then the deviations.
  sim::DamBreakJudgement j;
  if (sim::JudgeMartinMoyce(samples, measuredFront, measuredHeight, a, g, &j, tMin, tMax) && !j.front.empty()) {
    r->frontPoints = static_cast<int>(j.front.size());
    r->frontRms = j.frontRms;
    r->frontMax = j.frontMax;
    r->frontBias = j.frontBias;
    r->gateLag = j.lag;
    r->heightMax = j.height.empty() ? NAN : j.heightMax;
    r->frontTMin = j.front.front().t;
    r->frontTMax = j.front.back().t;
  }
  return true;
}

std::string Percent(double v) {
  if (!std::isfinite(v)) return "n/a";
  return Format("%.1f %%", 100.0 * v);
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
  SetLogLevel(LogLevel::kError);  // the soft stiffness warns about its sound speed: that is the point of the sweep
  const std::string header =
      "timestamp_utc,cpu_model,nproc,threads,load_avg_start,load_avg_end,mode,method,spacing_divisor,spacing_m,"
      "stiffness_factor,density_tolerance_pct,density_iterations,divergence_iterations,stiffness_pa,sound_speed,fluid,boundary,steps,dt_clamped_steps,clamped_events,sim_time_s,"
      "step_wall_s,loop_wall_s,wall_per_sim_s,front_rms_rel,front_max_rel,front_bias_rel,front_points,front_T_min,front_T_max,final_Z,"
      "gate_lag_ms,height_max_rel,"
      "mean_density_error,peak_mean_density_error,support_factor,viscosity,boundary_viscosity,floor_friction,cfl,"
      "max_dt,pbf_iterations";
  if (!args.csv.empty()) {  // before minutes of measuring
    if (const std::string why = CsvRefusal(args.csv, header); !why.empty()) {
      std::fprintf(stderr, "%s\n", why.c_str());
      return 1;
    }
  }

  std::vector<sim::DamBreakPoint> measuredFront, measuredHeight;
  if (!sim::ReadMartinMoyce(args.measurements, &measuredFront, &measuredHeight)) {
    std::fprintf(stderr, "%s: cannot read the front and height series of the Martin & Moyce measurements\n",
                 args.measurements.c_str());
    return 1;
  }

  std::vector<Config> configs;
  double tEnd = 0.235, tMin = 1.0, tMax = 3.3;  // tau = 3.05: the height series to tau = 3 as the test
  std::stringstream methods(args.methods);
  for (std::string name; std::getline(methods, name, ',');) {
    sim::SolverMethod m = sim::SolverMethod::kWcsph;
    sim::ParseSolverMethod(name, &m);
    const Knob& knob = KnobOf(m);
    if (args.quick) {
      for (int d : {14, 20}) configs.push_back({m, d, knob.quick});
    } else {
      for (int d : {14, 20, 26}) {
        for (double k : knob.values) configs.push_back({m, d, k});
      }
    }
  }
  if (args.quick) {
    tEnd = 0.05;
    tMin = 0.0;  // the smoke run ends at T = 0.93: compare what it reaches
  }

  const std::string model = CpuModel();
  const int cpus = CpuCount();
  const double loadStart = LoadAverage();
  const std::string when = UtcTimestamp();
  std::vector<Result> results;
  for (const Config& c : configs) {
    Result r;
    if (!Run(args, c, tEnd, tMin, tMax, measuredFront, measuredHeight, &r)) return 1;
    std::fprintf(stderr, "  %lld steps, %.1f s wall per simulated s, front RMS %s max %s, mean density error %.3f %%\n",
                 static_cast<long long>(r.steps), r.wallPerSimSecond, Percent(r.frontRms).c_str(),
                 Percent(r.frontMax).c_str(), 100.0 * r.meanDensityError);
    results.push_back(r);
  }
  const double loadEnd = LoadAverage();

  std::printf("\n## sphxr_bench_tradeoff%s\n\n", args.quick ? " (--quick: a smoke run, not a measurement)" : "");
  std::printf("- scene: %s to t = %g s (T = %.2f), CPU backend, the methods' own steps (WCSPH: CFL on c + v; DFSPH: CFL "
              "on v; PBF: 3 substeps a 1/90 s frame)\n", args.scene.c_str(), tEnd,
              tEnd * std::sqrt(2.0 * 9.81 / 0.05715));
  std::printf("- front error over the Martin & Moyce points with %g <= T <= %g reached by the run\n", tMin, tMax);
  std::printf("- machine: %s, nproc %d, solver threads %d; 1-min load average %.2f at start, %.2f at end; %s\n",
              model.c_str(), cpus, results.empty() ? 0 : results[0].threads, loadStart, loadEnd, when.c_str());
  if (!results.empty()) {
    const sim::SolverParams& p = results[0].params;
    std::printf("- the scene's other settings (shared by every run): support_factor %g, viscosity %g, boundary_viscosity "
                "%g, floor friction %s, cfl %g, max_dt %g s, exponent %g\n",
                p.supportFactor, p.viscosity, p.boundaryViscosity,
                results[0].friction.c_str(), p.cfl, p.maxDt,
                p.exponent);
  }
  if (loadStart > 0.5) {
    std::printf("- **the machine was busy (load average %.2f before the run): the wall times are not representative; "
                "the errors are**\n",
                loadStart);
  }
  std::printf("\n");
  std::printf("| method | spacing | stiffness, tolerance or iterations | fluid | steps | iterations (density, divergence) | wall s per "
              "simulated s | gate lag | front RMS error | front max error | front mean signed error | points | "
              "column height max error | mean density error | final Z |\n");
  std::printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Result& r : results) {
    std::string knob, iterations = "—";
    switch (r.config.method) {
      case sim::SolverMethod::kWcsph: knob = Format("x%g (%.0f Pa, c = %.1f m/s)", r.config.knob, r.stiffness, r.soundSpeed); break;
      case sim::SolverMethod::kDfsph:
        knob = Format("tolerance %g %%", r.config.knob);
        iterations = Format("%.1f, %.1f", r.densityIterations, r.divergenceIterations);
        break;
      case sim::SolverMethod::kPbf:
        knob = Format("%g iterations", r.config.knob);
        iterations = Format("%.0f, —", r.densityIterations);
        break;
    }
    std::printf("| %s | a/%d (%.3f mm) | %s | %d | %lld | %s | %.1f | %.2f ms | %s | %s | %s | %d | %s | %.3f %% | %.3f |\n",
                sim::SolverMethodName(r.config.method), r.config.spacingDivisor, 1e3 * r.spacing, knob.c_str(), r.fluid,
                static_cast<long long>(r.steps), iterations.c_str(), r.wallPerSimSecond, 1e3 * r.gateLag,
                Percent(r.frontRms).c_str(), Percent(r.frontMax).c_str(), Percent(r.frontBias).c_str(), r.frontPoints,
                Percent(r.heightMax).c_str(), 100.0 * r.meanDensityError, r.finalZ);
  }

  if (!args.csv.empty()) {
    std::ofstream csv;
    if (const std::string why = OpenCsv(args.csv, header, /*append=*/false, &csv); !why.empty()) {
      std::fprintf(stderr, "%s\n", why.c_str());
      return 1;
    }
    csv.precision(9);
    for (const Result& r : results) {
      csv << when << ',' << CsvField(model) << ',' << cpus << ',' << r.threads << ',' << loadStart << ',' << loadEnd << ','
          << (args.quick ? "quick" : "full") << ',' << sim::SolverMethodName(r.config.method) << ','
          << r.config.spacingDivisor << ',' << r.spacing << ','
          << (r.config.method == sim::SolverMethod::kWcsph ? r.config.knob : 1.0) << ','
          << (r.config.method == sim::SolverMethod::kDfsph ? Format("%g", r.config.knob) : std::string()) << ','
          << r.densityIterations << ',' << r.divergenceIterations << ',' << r.stiffness << ',' << r.soundSpeed << ',' << r.fluid << ',' << r.boundary
          << ',' << r.steps << ',' << r.dtClampedSteps << ',' << r.clampedEvents << ',' << r.simTime << ','
          << r.stepWall << ',' << r.loopWall << ',' << r.wallPerSimSecond << ',' << r.frontRms << ',' << r.frontMax
          << ',' << r.frontBias << ',' << r.frontPoints << ',' << r.frontTMin << ',' << r.frontTMax << ',' << r.finalZ << ','
          << 1e3 * r.gateLag << ',' << r.heightMax << ','
          << r.meanDensityError << ',' << r.peakMeanDensityError << ',' << r.params.supportFactor << ','
          << r.params.viscosity << ',' << r.params.boundaryViscosity << ','
          << r.friction << ',' << r.params.cfl << ','
          << r.params.maxDt << ','
          << (r.config.method == sim::SolverMethod::kPbf ? Format("%g", r.config.knob) : std::string()) << '\n';
    }
    std::printf("\nwrote %zu row(s) to %s\n", results.size(), args.csv.c_str());
  }
  return 0;
}
