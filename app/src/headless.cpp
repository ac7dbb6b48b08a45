#include "sphxr/app/headless.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>

#include "checkpoint_sink.h"
#include "dam_break_measure.h"
#include "export_sink.h"
#include "output_files.h"
#include "pictures_sink.h"
#include "progress.h"
#include "progress_sink.h"
#include "save_state_sink.h"
#include "stats_sink.h"
#include "summary_sink.h"
#include "interrupt_scope.h"
#include "sphxr/app/probe_csv.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/host_memory.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/openmp_wait.h"

namespace sphxr::app {
namespace {

/// What the run is to reach: --time / --steps, else the scene's run.time / run.steps.
struct Target {
  double time = 0.0;
  int64_t steps = 0;
};

/// What the steps asked of the device, per step (on cpu-reference: what the CUDA backend launches).
void PrintCounts(const RunSummary& summary) {
  const sim::LaunchCounts& c = summary.counts;
  const double steps = summary.steps > 0 ? static_cast<double>(summary.steps) : 1.0;
  std::printf("  device work     per step: %.1f launches, %.2f host waits, %.2f allocations, %.2f copies back (%.2f that no "
              "output asked for), %.2f uploads\n",
              c.launches / steps, c.syncs / steps, c.allocations / steps, c.downloads / steps,
              c.UnaskedDownloads() / steps, c.uploads / steps);
}

/// The summary's lines of the run itself: the scene, the particles, the device, the steps and the time,
/// the stages' cost, the density error and the speed.
void PrintRunLines(const Options& options, const SceneFile& scene, const Simulation& simulation, const RunSummary& s) {
  const RunSummary* summary = &s;
  const sim::Totals& totals = simulation.Solver().GetTotals();
  std::printf("sphxr summary: %s\n", scene.name.empty() ? ShowText(options.scenePath, std::string::npos).c_str() : ShowText(scene.name).c_str());
  std::printf("  particles       %d fluid, %d boundary\n", summary->fluid, summary->boundary);
  const sim::Device device = simulation.Solver().ActiveDevice();
  if (device == sim::Device::kCuda) {
    std::printf("  device          %s\n", sim::DeviceName(device));
  } else {  // how its OpenMP threads wait (docs/design/contention.md)
    std::printf("  device          %s (OpenMP wait: %s)\n", sim::DeviceName(device), ShowText(sim::OpenMpWaitSetting()).c_str());
  }
  std::printf("  steps           %lld (%lld with dt clamped to the stability limit)%s\n",
              static_cast<long long>(summary->steps), static_cast<long long>(totals.dtClampedSteps),
              summary->stepsBefore > 0 && summary->steps > 0 ? Format("; steps %lld to %lld of the whole run",
                                                static_cast<long long>(summary->stepsBefore + 1),
                                                static_cast<long long>(summary->stepsBefore + summary->steps))
                                             .c_str()
                                       : "");
  const double ran = summary->simulatedTime - summary->startTime;
  if (summary->startTime > 0.0) {
    std::printf("  simulated time  %.4f s to %.4f s (from the state file) in %.2f s wall (%.3f simulated s per wall s)\n",
                summary->startTime, summary->simulatedTime, summary->wallSeconds,
                summary->wallSeconds > 0 ? ran / summary->wallSeconds : 0.0);
  } else {
    std::printf("  simulated time  %.4f s in %.2f s wall (%.3f simulated s per wall s)\n", summary->simulatedTime,
                summary->wallSeconds, summary->wallSeconds > 0 ? ran / summary->wallSeconds : 0.0);
  }
  std::printf("  ms per step     %.3f total:", summary->msPerStep);
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    std::printf(" %s %.3f", sim::StageName(static_cast<sim::Stage>(s)), summary->stageMsPerStep[s]);
  }
  std::printf("\n");
  PrintCounts(*summary);
  std::printf("  density error   mean compression %.3f %% (peak over run %.3f %%); largest |rho/rho0 - 1| %.3f %% at the "
              "end (spray and surface particles are light)\n",
              100.0 * summary->meanDensityError, 100.0 * summary->peakMeanDensityError, 100.0 * summary->maxDensityError);
  std::printf("  max speed       %.3f m/s over the run\n", summary->maxSpeed);
}

/// The summary's lines of the models and what happened to the water: diffuse particles, reuse, the
/// settle, an interruption, clamped particles, the dam-break measures.
void PrintModelLines(const SceneFile& scene, const Target& target, const RunSummary& s) {
  const RunSummary* summary = &s;
  if (summary->diffuse[0] >= 0) {
    std::printf("  diffuse         %d spray, %d foam, %d bubbles at the end (solver.diffuse_capacity %g)\n",
                summary->diffuse[0], summary->diffuse[1], summary->diffuse[2], scene.setup.params.diffuseCapacity);
  }
  if (scene.setup.reuse.enabled) {
    std::printf("  reuse           on: %.1f %% of the particles computed per step on average (delta1 %g, delta2 %g, "
                "threshold %g, idle %d)\n",
                100.0 * summary->meanActiveFraction, scene.setup.reuse.delta1, scene.setup.reuse.delta2,
                scene.setup.reuse.threshold, scene.setup.reuse.idle);
  }
  if (summary->settle.steps > 0) {
    std::printf("  settled         %.4g s of energy minimisation before t = 0%s (%lld steps, %.2f s wall; largest |a| "
                "at the end %.3g m/s^2)\n",
                summary->settle.time, summary->settle.stopped ? ", stopped early" : "",
                static_cast<long long>(summary->settle.steps), summary->settle.wallSeconds, summary->settle.maxAccel);
  }
  if (summary->interrupted) {
    std::printf("  interrupted     by %s at t = %.4f s of the %s asked for\n", InterruptName(summary->interrupted),
                summary->simulatedTime,
                target.steps > 0 ? Format("%lld steps", static_cast<long long>(target.steps)).c_str()
                                 : Format("%.4g s", target.time).c_str());
  }
  std::printf("  particles lost  %lld (clamped back into the tank: %lld times, %.3g per 1,000 particle-steps%s%s)\n",
              static_cast<long long>(summary->lost), static_cast<long long>(summary->clampedEvents),
              summary->clampsPerThousand, summary->clampedMost.empty() ? "" : ", most at the ",
              summary->clampedMost.c_str());
  if (scene.damBreak) {
    std::printf("  dam break       surge front Z = %.3f, column height H = %.3f (Martin & Moyce units)\n",
                summary->surgeFront, summary->columnHeight);
  }
}

/// The summary's lines of the paddles (one each, then their means).
void PrintPaddleLines(const interaction::PaddleSystem& paddles, const RunSummary& summary) {
  for (int k = 0; k < paddles.Count(); ++k) {
    const interaction::PaddleDesc& d = paddles.Desc(k);
    const interaction::PaddleState& p = paddles.State(k);
    std::printf("  paddle          %s (%s): %d boundary particles, %s, filtered force [%.3g %.3g %.3g] N at the end, "
                "%lld teleport(s)\n",
                d.name.c_str(), interaction::HolderName(d.holder), paddles.ParticleCount(k),
                interaction::PaddleModeName(p.mode), p.force.x, p.force.y, p.force.z, static_cast<long long>(p.teleports));
  }
  std::printf("  paddles         mean filtered |force| %.3f N, peak haptic amplitude %.2f, fluid pushed out of a paddle "
              "%lld times\n",
              summary.paddleMeanForce, summary.paddlePeakHaptic, static_cast<long long>(summary.pushedOut));
}

/// The summary's lines of the files written.
void PrintOutputLines(const Options& options, const std::string& movie, bool picture, const RunSummary& s) {
  const RunSummary* summary = &s;
  if (summary->surfaceExports > 0) {
    std::printf("  surface         %lld meshes to %s, %.2f ms per extraction; the last %lld triangles\n",
                static_cast<long long>(summary->surfaceExports), ShowText(options.outDir, std::string::npos).c_str(), summary->surfaceMs,
                static_cast<long long>(summary->surfaceTriangles));
  }
  if (summary->frames > 0) {
    std::printf("  frames          %lld PNG files in %s%s%s\n", static_cast<long long>(summary->frames),
                ShowText(options.framesDir, std::string::npos).c_str(), movie.empty() ? "" : ", movie ", movie.c_str());
  }
  if (picture) {
    std::printf("  picture         %s (%dx%d)\n", ShowText(options.screenshotPath, std::string::npos).c_str(), options.imageWidth, options.imageHeight);
  }
  if (summary->exports > 0) {
    std::printf("  exported        %lld files to %s\n", static_cast<long long>(summary->exports), ShowText(options.outDir, std::string::npos).c_str());
  }
  if (summary->checkpoints > 0) {
    std::printf("  checkpoints     %lld, the last at t = %.6g s in %s%s\n", static_cast<long long>(summary->checkpoints),
                summary->checkpointTime, ShowText(options.saveState, std::string::npos).c_str(),
                summary->stateSaved.empty() ? "" : " (then replaced by the state at the end; older ones: .1, .2, ...)");
  }
  if (!summary->stateSaved.empty()) {
    std::printf("  state           saved to %s at t = %.6g s (sphxr --load-state %s continues from there)\n",
                summary->stateSaved.c_str(), summary->simulatedTime, summary->stateSaved.c_str());
  }
}

/// The summary printed at the end (stdout).
void PrintSummary(const Options& options, const SceneFile& scene, const Simulation& simulation, const Target& target,
                  const std::string& movie, bool picture, const RunSummary& summary) {
  PrintRunLines(options, scene, simulation, summary);
  PrintModelLines(scene, target, summary);
  if (const interaction::PaddleSystem* paddles = simulation.Paddles()) PrintPaddleLines(*paddles, summary);
  PrintOutputLines(options, movie, picture, summary);
}

/// The outputs' files, checked (and the CSV opened, the directories made, the GL context of the pictures
/// made) before the solver allocates anything, so a bad path costs nothing.
Status PrepareOutputs(const Options& options, const SceneFile& scene, RunSummary* summary,
                      std::unique_ptr<StatsSink>* stats, std::unique_ptr<PicturesSink>* pictures) {
  if (!options.statsPath.empty()) {
    *stats = std::make_unique<StatsSink>(options.statsPath);
    if (Status s = (*stats)->Open(); !s) return s;
  }
  // Files written after the run: check their places before it.
  if (Status s = CheckPlaceToWrite("--screenshot", options.screenshotPath, " (.png)"); !s) return s;
  if (Status s = CheckPlaceToWrite("--save-state", options.saveState, ""); !s) return s;
  const bool exporting = options.exportEvery > 0 || options.exportSurfaceEvery > 0 || options.exportInterval > 0.0 ||
                         options.exportSurfaceInterval > 0.0;
  if (options.outDir != Options{}.outDir && !exporting) {
    SPHXR_LOG_WARN("--out %s: nothing is exported without --export-every, --export-interval or their surface forms",
                   options.outDir.c_str());
  }
  if (exporting) {
    if (Status s = MakeOutputDirectory("--out", options.outDir); !s) return s;
  }
  if (!options.screenshotPath.empty() || !options.framesDir.empty()) {
    if (Status s = PicturesSink::Create(options, scene.surface, summary, pictures); !s) return s;
  }
  return Status::Ok();
}

/// The start's lines (a state file's, the particle counts) and the summary's counts.
void LogStart(const Options& options, const SceneFile& scene, const StateFile* state, const Simulation& simulation,
              RunSummary* summary) {
  const sim::Solver& solver = simulation.Solver();
  if (state) {
    SPHXR_LOG_INFO("started from %s: t = %.6g s, step %s, %d fluid particles (saved from '%s')",
                   options.loadState.c_str(), state->clock.time,
                   state->step < 0 ? "unknown" : std::to_string(state->step).c_str(), state->fluidCount,
                   state->scene.c_str());
    if (state->step < 0) {
      SPHXR_LOG_INFO("%s has no step count (a version-1 file, or continued from one): steps, exports and CSV rows "
                     "are numbered from 0 again, and a state saved from this run has no count either",
                     options.loadState.c_str());
    }
  }
  // Steps count on from the state's (the whole run's numbering): the CSV's step column, the export files'
  // numbers and the state saved at the end.
  summary->stepsBefore = std::max<int64_t>(simulation.StepsBefore(), 0);
  if (const interaction::PaddleSystem* paddles = simulation.Paddles()) {
    summary->paddles = paddles->Count();
    for (int k = 0; k < paddles->Count(); ++k) summary->paddleParticles += paddles->ParticleCount(k);
  }
  summary->startTime = solver.Time();
  const float spacing = scene.setup.params.spacing;
  summary->fluid = solver.FluidCount();
  summary->boundary = solver.BoundaryCount();
  SPHXR_LOG_INFO("%s: %d fluid + %d boundary particles, spacing %g m, device %s, sound speed %.3g m/s",
                 scene.name.empty() ? options.scenePath.c_str() : scene.name.c_str(), summary->fluid,
                 summary->boundary, spacing, sim::DeviceName(solver.ActiveDevice()), solver.SoundSpeed());
  if (summary->fluid == 0) {
    SPHXR_LOG_WARN("the scene has no fluid particles (no fluid block, or every block too thin or filled by "
                   "obstacles at spacing %g m): only the walls and paddles run", spacing);
  }
}

/// run.settle / --settle: Solver::Settle before the first step, with its own progress bar; a signal
/// stops it after the step in progress.
Status SettleFirst(double settle, bool showProgress, bool progressLines, sim::Solver& solver, RunSummary* summary) {
  if (settle <= 0.0) return Status::Ok();
  SPHXR_LOG_INFO("settling: %g simulated s of energy minimisation (FIRE) before t = 0", settle);
  Progress bar(showProgress, "settling ", progressLines);
  const auto t0 = std::chrono::steady_clock::now();
  auto update = [&](double done) {
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const int64_t steps = solver.GetTotals().steps;
    bar.Update(done / settle, done, steps, steps > 0 ? 1e3 * wall / static_cast<double>(steps) : 0.0);
    return !g_interrupt;
  };
  if (Status s = solver.Settle(settle, &summary->settle, update); !s) return Status::Error("--settle: " + s.message());
  bar.Finish();
  if (summary->settle.stopped) {
    SPHXR_LOG_WARN("settle stopped early at %.4g of %g s (%lld steps): the water is not settled", summary->settle.time,
                   settle, static_cast<long long>(summary->settle.steps));
  } else {
    SPHXR_LOG_INFO("settled: %.4g s in %lld steps (%.1f s wall); largest |a| at the end %.3g m/s^2; the run starts here",
                   summary->settle.time, static_cast<long long>(summary->settle.steps), summary->settle.wallSeconds,
                   summary->settle.maxAccel);
  }
  return Status::Ok();
}

/// The summary's figures of the run: the solver's totals, the sinks' measures, the last state's.
void Summarise(const SceneFile& scene, const sim::Solver& solver, const SummarySink& measures, const ExportSink& exports,
               RunSummary* summary) {
  const sim::Totals& totals = solver.GetTotals();
  summary->counts = solver.Counts() - summary->countsAtStart;
  summary->steps = totals.steps;
  summary->simulatedTime = solver.Time();
  summary->msPerStep = totals.steps > 0 ? 1e3 * totals.stepSeconds / totals.steps : 0.0;
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    summary->stageMsPerStep[s] = totals.steps > 0 ? 1e3 * totals.stageSeconds[s] / totals.steps : 0.0;
  }
  if (solver.Scene().params.diffuse > 0.0f) {
    sim::HostDiffuse diffuse;
    solver.DownloadDiffuse(&diffuse);
    for (int& k : summary->diffuse) k = 0;
    for (const sim::Vec4& v : diffuse.velocity) ++summary->diffuse[static_cast<int>(sim::DiffuseKindOf(v))];
  }
  summary->meanDensityError = solver.LastStep().meanDensityError;
  summary->maxDensityError = solver.LastStep().maxDensityError;
  summary->clampedEvents = totals.clampedEvents;
  if (totals.particleSteps > 0) {
    summary->clampsPerThousand = 1e3 * static_cast<double>(totals.clampedEvents) / static_cast<double>(totals.particleSteps);
  }
  if (totals.clampedEvents > 0) {
    const auto most = std::max_element(totals.clampedAt.begin(), totals.clampedAt.end());
    summary->clampedMost = sim::ClampSiteName(static_cast<int>(most - totals.clampedAt.begin()));
  }
  summary->pushedOut = totals.pushedOutEvents;
  if (summary->paddles > 0 && totals.steps > 0) {
    summary->paddleMeanForce = measures.ForceSum() / static_cast<double>(totals.steps * summary->paddles);
  }
  summary->meanActiveFraction = totals.steps > 0 ? measures.ActiveSum() / static_cast<double>(totals.steps) : 1.0;
  sim::HostFluid host;
  solver.Download(&host);
  summary->lost = summary->fluid - static_cast<int64_t>(host.size());
  if (scene.damBreak) {
    const DamBreakMeasure m = MeasureDamBreak(*scene.damBreak, host, scene.setup.params.spacing);
    summary->surgeFront = m.front;
    summary->columnHeight = m.height;
  }
  if (summary->surfaceExports > 0) {
    summary->surfaceMs = 1e3 * exports.SurfaceSeconds() / static_cast<double>(summary->surfaceExports);
  }
}

/// The scene with the command line's changes, the state file it starts from (read before anything is
/// allocated; it fixes the spacing, ReadStartState refuses a --spacing that differs, and replaces the
/// settle), the solver's configuration and what the run is to reach.
Status LoadRun(const Options& options, SceneFile* scene, std::shared_ptr<const StateFile>* state,
               SimulationConfig* config, Target* target) {
  {
    MemoryUse use("reading the scene (its file is at most 16 MiB)");
    if (Status s = LoadSceneWithOptions(options, scene); !s) return s;
  }
  if (options.checkpointEvery > 0.0 && options.saveState.empty()) {
    return Status::Error("--checkpoint-every: needs --save-state FILE (the checkpoints are that file)");
  }
  if (!options.loadState.empty() && options.settle > 0.0) {
    return Status::Error("--settle and --load-state: the state file is the start; settle in the run that saves it");
  }
  if (Status s = ReadStartState(options.loadState, ExplicitSpacing(options), scene->name, &scene->setup, state); !s) return s;
  config->solver.device = options.device;
  config->solver.threads = options.threads;
  config->solver.validate = options.validate;
  config->errorPrefix = options.scenePath + ": ";
  if (Status s = ApplyAutoQuality(options, options.quality == 1, state->get(), config->solver, &scene->setup); !s) return s;

  *target = Target{options.time, options.steps};
  if (target->time <= 0.0 && target->steps <= 0) *target = {scene->runTime, scene->runSteps};
  if (target->time <= 0.0 && target->steps <= 0) {
    return Status::Error(options.scenePath + ": the scene has no run.time or run.steps; give --time or --steps");
  }
  if (*state && target->steps <= 0 && (*state)->clock.time >= target->time - 1e-9) {
    return Status::Error(Format("--load-state %s: the state is at t = %.6g s, at or past the end time %g s (--time is "
                                "the end time on the state's clock)",
                                options.loadState.c_str(), (*state)->clock.time, target->time));
  }
  return Status::Ok();
}

/// The run's sinks, in the order they act after each step: the summary's measures, the CSV row, the
/// probes, a checkpoint (after the rows it keeps), the exports, the state at the end, pictures, progress.
/// Those with files (the CSVs, the pictures' GL context) are made before the solver allocates anything.
struct RunSinks {
  std::unique_ptr<StatsSink> stats;
  std::unique_ptr<ProbeSink> probes;
  std::unique_ptr<PicturesSink> pictures;
  std::unique_ptr<SummarySink> measures;
  std::unique_ptr<CheckpointSink> checkpoints;
  std::unique_ptr<ExportSink> exports;
  std::unique_ptr<SaveStateSink> save;
  std::unique_ptr<Progress> progress;
  std::unique_ptr<ProgressSink> progressSink;

  Status Open(const Options& options, const SceneFile& scene, const StateFile* state, RunSummary* summary) {
    if (!options.probesPath.empty()) {
      if (!scene.probes) {
        return Status::Error("--probes " + options.probesPath + ": " + options.scenePath +
                             " has no \"probes\" section (docs/user/scenes.md#probes)");
      }
      if (Status s = ProbeSink::Create(options.probesPath, *scene.probes, state ? state->clock.time : 0.0, &probes); !s) {
        return s;
      }
    }
    return PrepareOutputs(options, scene, summary, &stats, &pictures);
  }

  void Attach(const Options& options, const SceneFile& scene, double settle, const Target& target, bool showProgress,
              bool progressLines, RunSummary* summary, Simulation& simulation) {
    measures = std::make_unique<SummarySink>(summary);
    simulation.AddSink(measures.get());
    if (stats) simulation.AddSink(stats.get());
    if (probes) simulation.AddSink(probes.get());
    if (options.checkpointEvery > 0.0) {
      checkpoints = std::make_unique<CheckpointSink>(options, scene.name, stats.get(), summary);
      simulation.AddSink(checkpoints.get());
    }
    exports = std::make_unique<ExportSink>(options, scene.surface, summary);
    simulation.AddSink(exports.get());
    if (!options.saveState.empty()) {
      save = std::make_unique<SaveStateSink>(options, scene.name, settle, summary);
      simulation.AddSink(save.get());
    }
    if (pictures) simulation.AddSink(pictures.get());
    progress = std::make_unique<Progress>(showProgress, "", progressLines);
    progressSink = std::make_unique<ProgressSink>(progress.get(), target.steps, target.time, summary->startTime);
    simulation.AddSink(progressSink.get());
  }
};

/// The frames to the target time (the last one ends at the first step at or past it) or the steps to
/// the target count, or to a signal (then the run stops after the step in progress), and the sinks'
/// Finish: the rows of a run stopped by a signal too.
Status StepToTarget(Simulation& simulation, const Target& target, RunSinks& sinks, RunSummary* summary) {
  sim::Solver& solver = simulation.Solver();
  if (Status s = simulation.Start(); !s) return s;
  summary->countsAtStart = solver.Counts();
  if (target.steps > 0) {
    while (solver.GetTotals().steps < target.steps && !g_interrupt) {
      if (Status s = simulation.Step(); !s) return s;
    }
  } else {
    const auto running = [&] { return !g_interrupt && solver.Time() < target.time - 1e-9; };
    while (running()) {
      if (Status s = simulation.AdvanceFrame({}, running); !s) return s;
    }
  }
  summary->wallSeconds = sinks.progressSink->WallSeconds();
  summary->interrupted = g_interrupt;  // also a signal during the last step
  if (summary->interrupted) {
    sinks.progress->Finish();
    SPHXR_LOG_WARN("%s at step %lld (t = %.4f s): stopping; the summary and the files cover the run so far",
                   summary->interrupted == SIGINT    ? "interrupted (SIGINT)"
                   : summary->interrupted == SIGHUP ? "hung up (SIGHUP: the terminal closed)"
                                                    : "terminated (SIGTERM)",
                   static_cast<long long>(simulation.WholeStep()), solver.Time());
  }
  // A failed save is reported after the summary (which covers the run), not instead of it.
  return simulation.Finish(summary->interrupted != 0);
}

}  // namespace

Status RunHeadless(const Options& options, RunSummary* summary) {
  *summary = RunSummary{};
  SceneFile scene;
  std::shared_ptr<const StateFile> state;
  SimulationConfig config;
  Target target;
  if (Status s = LoadRun(options, &scene, &state, &config, &target); !s) return s;
  RunSinks sinks;
  if (Status s = sinks.Open(options, scene, state.get(), summary); !s) return s;

  SimScene simScene = SimSceneFromFile(scene);
  simScene.start = state;
  std::unique_ptr<Simulation> simulation;
  {
    MemoryUse use("the particles and the grid (use a larger --spacing or a smaller scene)");
    if (Status s = Simulation::Create(simScene, config, &simulation); !s) return s;
  }
  LogStart(options, scene, state.get(), *simulation, summary);
  state.reset();  // the solver and the paddles have it now
  simScene.start.reset();
  if (sinks.stats) {
    if (Status s = sinks.stats->WriteHeader(*simulation, scene.damBreak); !s) return s;
  }

  const bool showProgress = options.progress == 1 || (options.progress == -1 && isatty(STDERR_FILENO));
  const bool progressLines = options.progress == -1 && !showProgress;  // a log file: a line a minute
  // Ctrl-C/SIGTERM from here on stop the settling or the run after the step in progress.
  InterruptScope interruptScope;
  const double settle = options.loadState.empty() ? (options.settle >= 0.0 ? options.settle : scene.runSettle) : 0.0;
  if (!options.loadState.empty() && scene.runSettle > 0.0) {
    SPHXR_LOG_INFO("run.settle (%g s) skipped: the state file is the start", scene.runSettle);
  }
  if (Status s = SettleFirst(settle, showProgress, progressLines, simulation->Solver(), summary); !s) return s;
  sinks.Attach(options, scene, settle, target, showProgress, progressLines, summary, *simulation);
  if (Status s = StepToTarget(*simulation, target, sinks, summary); !s) return s;

  Summarise(scene, simulation->Solver(), *sinks.measures, *sinks.exports, summary);
  PrintSummary(options, scene, *simulation, target, sinks.pictures ? sinks.pictures->Movie() : std::string(),
               sinks.pictures && !options.screenshotPath.empty(), *summary);
  return sinks.save ? sinks.save->Saved() : Status::Ok();
}

}  // namespace sphxr::app
