#include "sphxr/app/headless.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>

#include "sphxr/app/export.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/measure.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::app {
namespace {

Status ParseDouble(const std::string& flag, const char* text, double lo, double hi, double* out) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (!*text || *end != '\0' || !std::isfinite(v)) return Status::Error(flag + " " + text + ": not a number");
  if (v < lo || v > hi) return Status::Error(Format("%s %s: must be from %g to %g", flag.c_str(), text, lo, hi));
  *out = v;
  return Status::Ok();
}

Status ParseInt(const std::string& flag, const char* text, int64_t lo, int64_t hi, int64_t* out) {
  char* end = nullptr;
  const long long v = std::strtoll(text, &end, 10);
  if (!*text || *end != '\0') return Status::Error(flag + " " + text + ": not an integer");
  if (v < lo || v > hi) {
    return Status::Error(Format("%s %s: must be from %lld to %lld", flag.c_str(), text, static_cast<long long>(lo),
                                static_cast<long long>(hi)));
  }
  *out = v;
  return Status::Ok();
}

/// A progress bar on a terminal, redrawn at most ten times a second.
class Progress {
 public:
  explicit Progress(bool enabled) : m_enabled(enabled) {}
  void Update(double fraction, double simTime, int64_t steps, double msPerStep) {
    if (!m_enabled) return;
    const auto now = std::chrono::steady_clock::now();
    if (fraction < 1.0 && now - m_last < std::chrono::milliseconds(100)) return;
    m_last = now;
    const int width = 30;
    const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
    std::fprintf(stderr, "\r[%.*s%.*s] %3d%%  t = %.4f s  step %lld  %.2f ms/step ", filled,
                 "##############################", width - filled, "                              ",
                 static_cast<int>(fraction * 100.0), simTime, static_cast<long long>(steps), msPerStep);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool m_enabled;
  std::chrono::steady_clock::time_point m_last{};
};

struct DamBreakMeasure {
  float front;   // Z = x_front / a
  float height;  // H = h / 2a
};

DamBreakMeasure MeasureDamBreak(const DamBreakProbe& probe, const sim::HostFluid& fluid, float spacing) {
  const int minPerBin = DamBreakMinPerBin(probe, spacing);
  DamBreakMeasure m;
  m.front = sim::SurgeFront(fluid, probe.wallX, spacing, minPerBin) / probe.columnWidth;
  m.height = sim::ColumnHeight(fluid, probe.floorY, probe.wallX, spacing, std::max(1, minPerBin / 2)) /
             (2.0f * probe.columnWidth);
  return m;
}

}  // namespace

std::string UsageText() {
  return "usage: sphxr [--headless] [--scene FILE] [--time S | --steps N] [--device auto|cpu|cuda]\n"
         "             [--threads T] [--spacing H] [--set KEY=VALUE]... [--export-every K --out DIR]\n"
         "             [--export-format ply|vtk] [--stats FILE.csv] [--validate] [--reuse on|off]\n"
         "             [--progress | --no-progress]\n"
         "\n"
         "  --headless        run without a window (the only mode until the renderer lands)\n"
         "  --scene FILE      JSON scene (default: " SPHXR_SCENES_DIR "/dam_break.json)\n"
         "  --time S          simulated seconds to run (default: the scene's run.time)\n"
         "  --steps N         number of steps instead of a time\n"
         "  --device D        auto (CUDA when a GPU answers, else CPU), cpu, or cuda\n"
         "  --threads T       CPU backend threads (0 = all cores)\n"
         "  --spacing H       particle spacing in m (rescales the particle count of the scene)\n"
         "  --set KEY=VALUE   a solver parameter of the scene's \"solver\" section, e.g. --set stiffness=2e5\n"
         "  --export-every K  write the particles every K steps to DIR (PLY or VTK: ParaView, Blender)\n"
         "  --stats FILE.csv  one CSV row per step (time, dt, speeds, density errors, probes)\n"
         "  --validate        check every stage for non-finite values; stop at the first, naming it\n"
         "  --reuse on|off    activity-based reuse (the scene's \"reuse\" section sets its parameters)\n";
}

Status ParseCommandLine(int argc, const char* const* argv, Options* out) {
  *out = Options{};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](const char** v) -> Status {
      if (i + 1 >= argc) return Status::Error(arg + ": missing value (see --help)");
      *v = argv[++i];
      return Status::Ok();
    };
    const char* v = nullptr;
    if (arg == "--help" || arg == "-h") {
      out->help = true;
    } else if (arg == "--headless") {
      out->mode = Mode::kHeadless;
    } else if (arg == "--desktop") {
      out->mode = Mode::kDesktop;
    } else if (arg == "--xr") {
      out->mode = Mode::kXr;
    } else if (arg == "--reuse") {
      if (Status s = value(&v); !s) return s;
      const std::string r = v;
      if (r != "on" && r != "off") return Status::Error("--reuse " + r + ": must be on or off");
      out->reuse = r == "on" ? 1 : 0;
    } else if (arg == "--validate") {
      out->validate = true;
    } else if (arg == "--progress") {
      out->progress = 1;
    } else if (arg == "--no-progress") {
      out->progress = 0;
    } else if (arg == "--scene") {
      if (Status s = value(&v); !s) return s;
      out->scenePath = v;
    } else if (arg == "--time") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseDouble(arg, v, 1e-9, 1e6, &out->time); !s) return s;
    } else if (arg == "--steps") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseInt(arg, v, 1, int64_t{1} << 40, &out->steps); !s) return s;
    } else if (arg == "--device") {
      if (Status s = value(&v); !s) return s;
      if (!sim::ParseDevice(v, &out->device)) return Status::Error(arg + " " + v + ": must be auto, cpu or cuda");
    } else if (arg == "--threads") {
      if (Status s = value(&v); !s) return s;
      int64_t t;
      if (Status s = ParseInt(arg, v, 0, 1024, &t); !s) return s;
      out->threads = static_cast<int>(t);
    } else if (arg == "--spacing") {
      if (Status s = value(&v); !s) return s;
      double h;
      const sim::ParamInfo* info = sim::FindSolverParam("spacing");
      if (Status s = ParseDouble(arg, v, info->min, info->max, &h); !s) return s;
      out->spacing = static_cast<float>(h);
    } else if (arg == "--set") {
      if (Status s = value(&v); !s) return s;
      out->sets.emplace_back(v);
    } else if (arg == "--export-every") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseInt(arg, v, 1, int64_t{1} << 40, &out->exportEvery); !s) return s;
    } else if (arg == "--out") {
      if (Status s = value(&v); !s) return s;
      out->outDir = v;
    } else if (arg == "--export-format") {
      if (Status s = value(&v); !s) return s;
      out->exportFormat = v;
      if (out->exportFormat != "ply" && out->exportFormat != "vtk") {
        return Status::Error(arg + " " + v + ": must be ply or vtk");
      }
    } else if (arg == "--stats") {
      if (Status s = value(&v); !s) return s;
      out->statsPath = v;
    } else {
      return Status::Error("unknown argument '" + arg + "' (see --help)");
    }
  }
  if (out->time > 0.0 && out->steps > 0) return Status::Error("--time and --steps: give one, not both");
  if (out->scenePath.empty()) out->scenePath = SPHXR_SCENES_DIR "/dam_break.json";
  return Status::Ok();
}

Status RunHeadless(const Options& options, RunSummary* summary) {
  *summary = RunSummary{};
  SceneFile scene;
  if (Status s = LoadScene(options.scenePath, &scene); !s) return s;
  for (const std::string& set : options.sets) {
    if (Status s = SetSolverParam(&scene.setup, set); !s) return s;
  }
  if (options.spacing > 0.0f) scene.setup.params.spacing = options.spacing;
  if (options.reuse >= 0) scene.setup.reuse.enabled = options.reuse == 1;

  double targetTime = options.time;
  int64_t targetSteps = options.steps;
  if (targetTime <= 0.0 && targetSteps <= 0) {
    targetTime = scene.runTime;
    targetSteps = scene.runSteps;
  }
  if (targetTime <= 0.0 && targetSteps <= 0) {
    return Status::Error(options.scenePath + ": the scene has no run.time or run.steps; give --time or --steps");
  }

  // Files are opened before the solver allocates anything, so a bad path costs nothing.
  std::ofstream stats;
  if (!options.statsPath.empty()) {
    stats.open(options.statsPath);
    if (!stats) return Status::Error("--stats " + options.statsPath + ": cannot open for writing");
  }
  if (options.exportEvery > 0) {
    std::error_code ec;
    std::filesystem::create_directories(options.outDir, ec);
    if (ec) return Status::Error("--out " + options.outDir + ": cannot create the directory: " + ec.message());
  }

  sim::SolverConfig config;
  config.device = options.device;
  config.threads = options.threads;
  config.validate = options.validate;
  std::unique_ptr<sim::Solver> solver;
  if (Status s = sim::Solver::Create(scene.setup, config, &solver); !s) return Status::Error(options.scenePath + ": " + s.message());

  const float spacing = scene.setup.params.spacing;
  summary->fluid = solver->FluidCount();
  summary->boundary = solver->BoundaryCount();
  SPHXR_LOG_INFO("%s: %d fluid + %d boundary particles, spacing %g m, device %s, sound speed %.3g m/s",
                 scene.name.empty() ? options.scenePath.c_str() : scene.name.c_str(), summary->fluid,
                 summary->boundary, spacing, sim::DeviceName(solver->ActiveDevice()), solver->SoundSpeed());

  const bool probeEveryStep = scene.damBreak.has_value() && stats.is_open();
  if (stats) {
    stats << "step,time,dt,max_speed,mean_density_error,max_density_error,clamped,active_fraction";
    if (probeEveryStep) stats << ",front_Z,height_H";
    stats << "\n";
  }

  Progress progress(options.progress == 1 || (options.progress == -1 && isatty(STDERR_FILENO)));
  sim::HostFluid host;
  auto exportNow = [&](int64_t step) -> Status {
    solver->Download(&host);
    char name[64];
    std::snprintf(name, sizeof(name), "particles_%06lld.%s", static_cast<long long>(step), options.exportFormat.c_str());
    const std::string path = (std::filesystem::path(options.outDir) / name).string();
    Status s = options.exportFormat == "vtk" ? WriteVtk(path, host) : WritePly(path, host);
    if (s) ++summary->exports;
    return s;
  };
  if (options.exportEvery > 0) {
    if (Status s = exportNow(0); !s) return s;
  }

  double activeSum = 0.0;
  const auto begin = std::chrono::steady_clock::now();
  while (targetSteps > 0 ? solver->GetTotals().steps < targetSteps : solver->Time() < targetTime - 1e-9) {
    if (Status s = solver->Step(); !s) return s;
    const sim::StepInfo& info = solver->LastStep();
    const int64_t step = solver->GetTotals().steps;
    summary->peakMeanDensityError = std::max(summary->peakMeanDensityError, info.meanDensityError);
    summary->maxSpeed = std::max(summary->maxSpeed, info.maxSpeed);
    activeSum += info.activeFraction;
    if (!std::isfinite(info.maxSpeed)) {
      return Status::Error(Format("the simulation became non-finite at step %lld (t = %.4g s); rerun with --validate "
                                  "to find the stage and particle, and lower solver.fixed_dt or raise solver.stiffness",
                                  static_cast<long long>(step), info.time));
    }
    if (stats) {
      stats << step << ',' << info.time << ',' << info.dt << ',' << info.maxSpeed << ',' << info.meanDensityError << ','
            << info.maxDensityError << ',' << info.clamped << ',' << info.activeFraction;
      if (probeEveryStep) {
        solver->Download(&host);
        const DamBreakMeasure m = MeasureDamBreak(*scene.damBreak, host, spacing);
        stats << ',' << m.front << ',' << m.height;
      }
      stats << '\n';
    }
    if (options.exportEvery > 0 && step % options.exportEvery == 0) {
      if (Status s = exportNow(step); !s) return s;
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    const double fraction = targetSteps > 0 ? static_cast<double>(step) / targetSteps : solver->Time() / targetTime;
    progress.Update(std::min(1.0, fraction), solver->Time(), step, 1e3 * wall / step);
  }
  summary->wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();

  const sim::Totals& totals = solver->GetTotals();
  summary->steps = totals.steps;
  summary->simulatedTime = solver->Time();
  summary->msPerStep = totals.steps > 0 ? 1e3 * totals.stepSeconds / totals.steps : 0.0;
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    summary->stageMsPerStep[s] = totals.steps > 0 ? 1e3 * totals.stageSeconds[s] / totals.steps : 0.0;
  }
  summary->meanDensityError = solver->LastStep().meanDensityError;
  summary->maxDensityError = solver->LastStep().maxDensityError;
  summary->clampedEvents = totals.clampedEvents;
  summary->meanActiveFraction = totals.steps > 0 ? activeSum / static_cast<double>(totals.steps) : 1.0;
  solver->Download(&host);
  summary->lost = summary->fluid - static_cast<int64_t>(host.size());
  if (scene.damBreak) {
    const DamBreakMeasure m = MeasureDamBreak(*scene.damBreak, host, spacing);
    summary->surgeFront = m.front;
    summary->columnHeight = m.height;
  }

  std::printf("sphxr summary: %s\n", scene.name.empty() ? options.scenePath.c_str() : scene.name.c_str());
  std::printf("  particles       %d fluid, %d boundary\n", summary->fluid, summary->boundary);
  std::printf("  device          %s\n", sim::DeviceName(solver->ActiveDevice()));
  std::printf("  steps           %lld (%lld with dt clamped to the stability limit)\n",
              static_cast<long long>(summary->steps), static_cast<long long>(totals.dtClampedSteps));
  std::printf("  simulated time  %.4f s in %.2f s wall (%.3f simulated s per wall s)\n", summary->simulatedTime,
              summary->wallSeconds, summary->wallSeconds > 0 ? summary->simulatedTime / summary->wallSeconds : 0.0);
  std::printf("  ms per step     %.3f total:", summary->msPerStep);
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    std::printf(" %s %.3f", sim::StageName(static_cast<sim::Stage>(s)), summary->stageMsPerStep[s]);
  }
  std::printf("\n");
  std::printf("  density error   mean compression %.3f %% (peak over run %.3f %%); largest |rho/rho0 - 1| %.3f %% at the "
              "end (spray and surface particles are light)\n",
              100.0 * summary->meanDensityError, 100.0 * summary->peakMeanDensityError, 100.0 * summary->maxDensityError);
  std::printf("  max speed       %.3f m/s over the run\n", summary->maxSpeed);
  if (scene.setup.reuse.enabled) {
    std::printf("  reuse           on: %.1f %% of the particles computed per step on average (delta1 %g, delta2 %g, "
                "threshold %g, idle %d)\n",
                100.0 * summary->meanActiveFraction, scene.setup.reuse.delta1, scene.setup.reuse.delta2,
                scene.setup.reuse.threshold, scene.setup.reuse.idle);
  }
  std::printf("  particles lost  %lld (clamped back into the tank: %lld times)\n", static_cast<long long>(summary->lost),
              static_cast<long long>(summary->clampedEvents));
  if (scene.damBreak) {
    std::printf("  dam break       surge front Z = %.3f, column height H = %.3f (Martin & Moyce units)\n",
                summary->surgeFront, summary->columnHeight);
  }
  if (summary->exports > 0) {
    std::printf("  exported        %lld files to %s\n", static_cast<long long>(summary->exports), options.outDir.c_str());
  }
  return Status::Ok();
}

}  // namespace sphxr::app
