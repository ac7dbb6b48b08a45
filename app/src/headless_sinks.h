#pragma once
#include <span>

#include "sphxr/sim/solver_table.h"
// The headless runner's outputs, each a sink of the Simulation (simulation.h): the stats CSV, particle
// and surface exports, pictures (--frames, --screenshot), checkpoints, the progress bar and the
// summary's per-step measures. They are made (and their files checked) before the solver allocates
// anything, so a bad path costs nothing.
#include <chrono>
#include <cstdint>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "sphxr/app/cli.h"
#include "sphxr/app/headless.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

/// Progress of a long run: a bar redrawn in place on a terminal, or (`lines`: stderr is a log file, the
/// default when it is not a terminal) one line a minute, so a run logged to a file is not silent for
/// minutes. Both say how long is left, extrapolated from the wall time so far.
class Progress {
 public:
  explicit Progress(bool enabled, const char* label = "", bool lines = false)
      : m_enabled(enabled), m_lines(lines && !enabled), m_label(label) {}
  void Update(double fraction, double simTime, int64_t steps, double msPerStep);
  /// Ends a bar left unfinished (a run stopped early), so that the next line starts on its own.
  void Finish();

 private:
  std::string Left(double fraction, std::chrono::steady_clock::time_point now) const;

  bool m_enabled;
  bool m_lines;
  const char* m_label;
  bool m_open = false;
  std::chrono::steady_clock::time_point m_start{}, m_last{};
};

/// A file that `flag` writes after the run: not a directory, in a directory we may write into (an
/// empty path: nothing to check).
Status CheckPlaceToWrite(const std::string& flag, const std::string& path, const char* nameHint);
/// An output directory: made when missing, but only in a directory that exists (a typo, or a path
/// under /, must not make a tree of directories, as root anywhere).
Status MakeOutputDirectory(const std::string& flag, const std::string& dir);

struct DamBreakMeasure {
  float front;   // Z = x_front / a
  float height;  // H = h / 2a
};
DamBreakMeasure MeasureDamBreak(const DamBreakProbe& probe, const sim::HostFluid& fluid, float spacing);

/// The summary's measures over the run (RunSummary: peaks, the mean active fraction, the paddles' mean
/// force and peak haptic amplitude).
class SummarySink : public SimulationSink {
 public:
  explicit SummarySink(RunSummary* summary) : m_summary(summary) {}
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  double ActiveSum() const { return m_activeSum; }
  double ForceSum() const { return m_forceSum; }

 private:
  RunSummary* m_summary;
  double m_activeSum = 0.0;
  double m_forceSum = 0.0;
};

/// --stats FILE.csv: one row per step. The rows are held and handed to the file at least once a second of
/// wall time (and before each checkpoint, and at the end, also of a run stopped by a signal), so that a
/// kill loses at most a second of rows and never leaves half a row.
class StatsSink : public SimulationSink {
 public:
  explicit StatsSink(std::string path) : m_path(std::move(path)) {}
  /// Before the solver exists: the file is opened without truncating it (a run continued from a state
  /// file keeps the first half's rows; a run refused at start-up leaves the file as it was).
  Status Open();
  /// After Create: the header, or the first half's rows kept when they continue into this run.
  Status WriteHeader(Simulation& simulation, const std::optional<DamBreakProbe>& probe);
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  /// Hands the held rows to the file; an error names --stats.
  Status Flush();
  Status Finish(Simulation& simulation, bool interrupted) override;

 private:
  /// After a failed write: the file cut after its last whole row (a full disk leaves no half row).
  void CutToWholeRows();

  std::string m_path;
  std::ofstream m_out;
  int64_t m_whole = -1;  // bytes of the file known to end at a whole row; -1: not a regular file
  std::optional<DamBreakProbe> m_probe;
  std::span<const sim::SolveColumn> m_stats;  // the method's own columns (its solver-table row)
  std::string m_pending;
  std::chrono::steady_clock::time_point m_last = std::chrono::steady_clock::now();
  sim::HostFluid m_host;
};

/// --checkpoint-every S: the state saved to the --save-state file at whole multiples of S on the simulated
/// clock, the --checkpoint-keep - 1 before it moved to FILE.1 (the newest), FILE.2, ...
class CheckpointSink : public SimulationSink {
 public:
  CheckpointSink(const Options& options, std::string sceneName, StatsSink* stats, RunSummary* summary)
      : m_options(options), m_sceneName(std::move(sceneName)), m_stats(stats), m_summary(summary) {}
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;

 private:
  const Options& m_options;
  std::string m_sceneName;
  StatsSink* m_stats;  // may be null
  RunSummary* m_summary;
  double m_next = 0.0;
};

/// --save-state FILE: the state at the end of the run (also of one stopped by a signal). A failed save
/// does not stop the others' Finish: it is reported after the summary (Saved()), which covers the run.
class SaveStateSink : public SimulationSink {
 public:
  SaveStateSink(const Options& options, std::string sceneName, double settle, RunSummary* summary)
      : m_options(options), m_sceneName(std::move(sceneName)), m_settle(settle), m_summary(summary) {}
  Status OnStep(Simulation&, const sim::StepInfo&) override { return Status::Ok(); }
  Status Finish(Simulation& simulation, bool interrupted) override;
  const Status& Saved() const { return m_saved; }

 private:
  const Options& m_options;
  std::string m_sceneName;
  double m_settle;
  RunSummary* m_summary;
  Status m_saved;
};

/// --export-every K and --export-surface-every K: particles (PLY, VTK) and the surface mesh (PLY, OBJ)
/// into --out DIR, at the start when its step is one of theirs, every K steps, and once more at the
/// step a signal stopped the run. --export-interval S and --export-surface-interval S instead: at the
/// first step at or after each multiple of S simulated seconds (the start when it is one). Every file
/// names its step and time (export.h ExportStamp).
class ExportSink : public SimulationSink {
 public:
  ExportSink(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary)
      : m_options(options), m_surface(surface), m_summary(summary) {}
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  Status Finish(Simulation& simulation, bool interrupted) override;
  /// Mean extraction time in s, over the surfaces exported.
  double SurfaceSeconds() const { return m_surfaceSeconds; }

 private:
  Status Particles(Simulation& simulation, int64_t step);
  Status Surface(Simulation& simulation, int64_t step);
  /// The exports due now, by step count or by simulated time.
  Status Due(Simulation& simulation);
  /// By time: the multiple `*next` of `interval` is reached at `time`; moves `*next` past it.
  static bool Reached(double interval, double time, int64_t* next);

  const Options& m_options;
  std::optional<sim::SurfaceParams> m_surface;
  RunSummary* m_summary;
  sim::HostFluid m_host;
  sim::HostDiffuse m_diffuse;
  sim::SurfaceMesh m_mesh;
  double m_surfaceSeconds = 0.0;
  int64_t m_nextParticles = 0, m_nextSurface = 0;      // by time: the next multiple of the interval
  int64_t m_particlesStep = -1, m_surfaceStep = -1;    // the step of the last file written
};

/// --frames DIR (a PNG every 1/fps simulated s, then DIR/movie.mp4 when ffmpeg is on the PATH) and
/// --screenshot FILE.png (the last state). The GL context is made by Create, before the run, so a
/// machine without EGL fails in a second.
class PicturesSink : public SimulationSink {
 public:
  static Status Create(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary,
                       std::unique_ptr<PicturesSink>* out);
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  /// The movie and the screenshot.
  Status Finish(Simulation& simulation, bool interrupted) override;
  /// DIR/movie.mp4 when Finish made it, else empty.
  const std::string& Movie() const { return m_movie; }

 private:
  PicturesSink(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary)
      : m_options(options), m_surface(surface), m_summary(summary) {}
  Status Picture(Simulation& simulation, const std::string& path);
  Status DueFrames(Simulation& simulation);

  const Options& m_options;
  std::optional<sim::SurfaceParams> m_surface;
  RunSummary* m_summary;
  std::unique_ptr<OfflinePictures> m_pictures;
  SimSnapshot m_snap;
  int64_t m_frameIndex = 0;
  int64_t m_firstFrame = 0;
  std::string m_movie;
};

/// The progress bar (or a line a minute) of the steps towards the run's end.
class ProgressSink : public SimulationSink {
 public:
  ProgressSink(Progress* progress, int64_t targetSteps, double targetTime, double startTime)
      : m_progress(progress), m_targetSteps(targetSteps), m_targetTime(targetTime), m_startTime(startTime) {}
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  /// Wall seconds since OnStart.
  double WallSeconds() const;

 private:
  Progress* m_progress;
  int64_t m_targetSteps;
  double m_targetTime;
  double m_startTime;
  std::chrono::steady_clock::time_point m_begin{};
};

}  // namespace sphxr::app
