#include "headless_sinks.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "csv_continue.h"
#include "sphxr/app/export.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/measure.h"

namespace sphxr::app {
namespace {

/// How much of an earlier `--stats` file a run continued from a state saved at step `stepsBefore`
/// keeps: the bytes of the header and the rows up to that step, when it is a regular file with this
/// run's header, rows in step order and a row for that step (the first half's CSV); else -1, and the
/// file is written anew. `*dropped` counts the rows after that step (a second half run before).
int64_t StatsBytesToKeep(const std::string& path, const std::string& header, int64_t stepsBefore, int64_t* dropped) {
  *dropped = 0;
  if (stepsBefore <= 0) return -1;
  long long previous = 0;
  bool found = false;  // the row of the state's step itself
  const int64_t keep = CsvBytesToKeep(path, header, [&](const std::string& line) {
    char* end = nullptr;
    const long long step = std::strtoll(line.c_str(), &end, 10);
    if (end == line.c_str() || *end != ',' || step <= previous) return RowFate::kForeign;  // not ours, or not in order
    previous = step;
    if (step > stepsBefore) return RowFate::kDrop;
    found = step == stepsBefore;
    return RowFate::kKeep;
  }, dropped);
  return found ? keep : -1;
}

}  // namespace

void Progress::Update(double fraction, double simTime, int64_t steps, double msPerStep) {
  if (!m_enabled && !m_lines) return;
  const auto now = std::chrono::steady_clock::now();
  if (m_start == std::chrono::steady_clock::time_point{}) m_start = now;
  if (m_lines) {
    if (fraction >= 1.0 || now - m_last < std::chrono::seconds(60)) return;
    if (m_last == std::chrono::steady_clock::time_point{}) {  // the first line a minute in, not at once
      m_last = now;
      return;
    }
    m_last = now;
    SPHXR_LOG_INFO("%s%d %%: t = %.4f s, step %lld, %.2f ms/step%s", m_label, static_cast<int>(fraction * 100.0),
                   simTime, static_cast<long long>(steps), msPerStep, Left(fraction, now).c_str());
    return;
  }
  if (fraction < 1.0 && now - m_last < std::chrono::milliseconds(100)) return;
  m_last = now;
  const int width = 30;
  const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
  std::fprintf(stderr, "\r%s[%.*s%.*s] %3d%%  t = %.4f s  step %lld  %.2f ms/step%s ", m_label, filled,
               "##############################", width - filled, "                              ",
               static_cast<int>(fraction * 100.0), simTime, static_cast<long long>(steps), msPerStep,
               fraction < 1.0 ? Left(fraction, now).c_str() : "");
  m_open = fraction < 1.0;
  if (!m_open) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

void Progress::Finish() {
  if (m_open) std::fprintf(stderr, "\n");
  m_open = false;
}

// ", about 3 min left" once two seconds and a thousandth of the run have passed.
std::string Progress::Left(double fraction, std::chrono::steady_clock::time_point now) const {
  const double elapsed = std::chrono::duration<double>(now - m_start).count();
  if (elapsed < 2.0 || fraction < 1e-3) return {};
  const double left = elapsed * (1.0 - fraction) / fraction;
  if (left < 90.0) return Format(", about %.0f s left", left);
  if (left < 5400.0) return Format(", about %.0f min left", left / 60.0);
  return Format(", about %.1f h left", left / 3600.0);
}

DamBreakMeasure MeasureDamBreak(const DamBreakProbe& probe, const sim::HostFluid& fluid, float spacing) {
  const int minPerBin = DamBreakMinPerBin(probe, spacing);
  DamBreakMeasure m;
  m.front = sim::SurgeFront(fluid, probe.wallX, spacing, minPerBin) / probe.columnWidth;
  m.height = sim::ColumnHeight(fluid, probe.floorY, probe.wallX, spacing, std::max(1, minPerBin / 2)) /
             (2.0f * probe.columnWidth);
  return m;
}

Status CheckPlaceToWrite(const std::string& flag, const std::string& path, const char* nameHint) {
  if (path.empty()) return Status::Ok();
  const std::filesystem::path file(path);
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    return Status::Error(flag + " " + path + ": is a directory; give a file name" + nameHint);
  }
  // (These files are replaced whole: a device or a pipe there is not a place for them.)
  if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec)) {
    return Status::Error(flag + " " + path + ": not a regular file (a device or pipe); give a file name" + nameHint);
  }
  if (!std::filesystem::is_directory(dir, ec) || access(dir.c_str(), W_OK) != 0) {
    return Status::Error(flag + " " + path + ": cannot write into " + dir.string());
  }
  return Status::Ok();
}

Status MakeOutputDirectory(const std::string& flag, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return Status::Ok();
  if (fs::exists(dir, ec)) return Status::Error(flag + " " + ShowText(dir) + ": exists and is not a directory");
  fs::path normal = fs::path(dir).lexically_normal();
  if (!normal.has_filename()) normal = normal.parent_path();  // "out/"
  const fs::path parent = normal.parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec)) {
    return Status::Error(flag + " " + ShowText(dir) + ": " + ShowText(parent.string()) + " does not exist; make it first");
  }
  fs::create_directory(dir, ec);
  if (ec) return Status::Error(flag + " " + ShowText(dir) + ": cannot create the directory: " + ec.message());
  return Status::Ok();
}

// ---- summary ---------------------------------------------------------------------------------------

Status SummarySink::OnStep(Simulation& simulation, const sim::StepInfo& info) {
  if (const interaction::PaddleSystem* paddles = simulation.Paddles()) {
    for (int k = 0; k < paddles->Count(); ++k) {
      m_forceSum += Length(paddles->State(k).force);
      m_summary->paddlePeakHaptic = std::max(m_summary->paddlePeakHaptic, paddles->State(k).haptic);
    }
  }
  m_summary->peakMeanDensityError = std::max(m_summary->peakMeanDensityError, info.meanDensityError);
  m_summary->maxSpeed = std::max(m_summary->maxSpeed, info.maxSpeed);
  m_activeSum += info.activeFraction;
  return Status::Ok();
}

// ---- stats CSV -------------------------------------------------------------------------------------

Status StatsSink::Open() {
  const std::filesystem::path parent = std::filesystem::path(m_path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec)) {
    return Status::Error("--stats " + ShowText(m_path) + ": " + ShowText(parent.string()) + " does not exist; make it first");
  }
  m_out.open(m_path, std::ios::app);
  if (!m_out) return Status::Error("--stats " + ShowText(m_path) + ": cannot open for writing");
  return Status::Ok();
}

Status StatsSink::WriteHeader(Simulation& simulation, const std::optional<DamBreakProbe>& probe) {
  m_probe = probe;
  m_stats = sim::SolverInfoOf(simulation.Solver().Method()).columns;
  const interaction::PaddleSystem* paddles = simulation.Paddles();
  std::string header = "step,time,dt,max_speed,mean_density_error,max_density_error,clamped,active_fraction";
  if (m_probe) header += ",front_Z,height_H";
  for (const sim::SolveColumn& column : m_stats) header += std::string(",") + column.name;
  if (paddles) {
    header += ",pushed_out";
    for (int k = 0; k < paddles->Count(); ++k) header += Format(",paddle%d_fx,paddle%d_fy,paddle%d_fz,paddle%d_haptic", k, k, k, k);
  }
  // A continued run appends to the first half's CSV: the whole run's rows in one file. The first half's
  // rows are never rewritten: later rows (of an earlier continuation) are cut off, then rows appended.
  // A pipe or device is written as it was opened (never read back, never reopened).
  const int64_t stepsBefore = std::max<int64_t>(simulation.StepsBefore(), 0);
  int64_t dropped = 0;
  const int64_t keep = StatsBytesToKeep(m_path, header, stepsBefore, &dropped);
  std::error_code ec;
  if (keep >= 0) {
    m_out.close();
    if (dropped > 0) std::filesystem::resize_file(m_path, static_cast<uintmax_t>(keep), ec);
    if (!ec) m_out.open(m_path, std::ios::app);
    if (ec || !m_out) return Status::Error("--stats " + ShowText(m_path) + ": cannot continue the file: " + ec.message());
    SPHXR_LOG_INFO("--stats %s: the rows continue the earlier run's (its steps up to %lld kept%s)", m_path.c_str(),
                   static_cast<long long>(stepsBefore),
                   dropped > 0 ? Format(", %lld rows after it replaced", static_cast<long long>(dropped)).c_str() : "");
  } else {
    // A continued run whose file holds the first half's rows under other columns (another method's
    // statistics, other paddles) would rewrite them: refused, the file left as it is.
    if (stepsBefore > 0) {
      std::string first;
      std::ifstream earlier(m_path, std::ios::binary);
      if (std::filesystem::is_regular_file(m_path, ec) && std::getline(earlier, first) &&
          first.rfind("step,time,", 0) == 0 && first != header) {
        return Status::Error("--stats " + ShowText(m_path) + ": the earlier run's rows there have other columns (" +
                             ShowText(first.substr(first.find(',', 10) + 1), 60) +
                             "; this run's: " + ShowText(header.substr(header.find(',', 10) + 1), 60) +
                             "): continuing into it would rewrite them; give another --stats file");
      }
    }
    if (std::filesystem::is_regular_file(m_path, ec)) {
      m_out.close();
      m_out.open(m_path, std::ios::trunc);
      if (!m_out) return Status::Error("--stats " + ShowText(m_path) + ": cannot open for writing");
    }
    m_out << header << "\n";
  }
  m_out.flush();
  m_whole =
      std::filesystem::is_regular_file(m_path, ec) ? static_cast<int64_t>(std::filesystem::file_size(m_path, ec)) : -1;
  if (ec) m_whole = -1;
  return Status::Ok();
}

Status StatsSink::OnStep(Simulation& simulation, const sim::StepInfo& info) {
  const int64_t wholeStep = simulation.WholeStep();
  std::ostringstream row;
  row << wholeStep << ',' << info.time << ',' << info.dt << ',' << info.maxSpeed << ',' << info.meanDensityError << ','
      << info.maxDensityError << ',' << info.clamped << ',' << info.activeFraction;
  if (m_probe) {
    simulation.Solver().Download(&m_host);
    const DamBreakMeasure m = MeasureDamBreak(*m_probe, m_host, simulation.Setup().params.spacing);
    row << ',' << m.front << ',' << m.height;
  }
  for (const sim::SolveColumn& column : m_stats) row << ',' << column.Value(info.solve);
  if (const interaction::PaddleSystem* paddles = simulation.Paddles()) {
    row << ',' << info.pushedOut;
    for (int k = 0; k < paddles->Count(); ++k) {
      const interaction::PaddleState& p = paddles->State(k);
      row << ',' << p.force.x << ',' << p.force.y << ',' << p.force.z << ',' << p.haptic;
    }
  }
  row << '\n';
  m_pending += row.str();
  const bool due = m_pending.size() > (size_t{1} << 20) || std::chrono::steady_clock::now() - m_last >= std::chrono::seconds(1);
  if (due) {
    if (Status s = Flush(); !s) return Status::Error(s.message() + " (at step " + std::to_string(wholeStep) + ")");
  }
  return Status::Ok();
}

Status StatsSink::Flush() {
  m_last = std::chrono::steady_clock::now();
  if (m_pending.empty() || !m_out.is_open()) return Status::Ok();
  errno = 0;
  m_out.write(m_pending.data(), static_cast<std::streamsize>(m_pending.size()));
  m_out.flush();
  const int error = errno;
  const size_t written = m_pending.size();
  m_pending.clear();
  if (!m_out) {
    m_out.close();  // nothing more is written: what reached the file ends at its last whole row
    CutToWholeRows();
    return Status::Error("--stats " + ShowText(m_path) + ": write failed (" +
                         (error ? std::strerror(error) : "disk full?") + "); the file ends at its last whole row");
  }
  if (m_whole >= 0) m_whole += static_cast<int64_t>(written);
  return Status::Ok();
}

void StatsSink::CutToWholeRows() {
  // A regular file only (a pipe or a device has nothing to cut): the bytes after the last whole row
  // known to be written, up to the last newline among them, are kept.
  if (m_whole < 0) return;
  std::error_code ec;
  const auto size = static_cast<int64_t>(std::filesystem::file_size(m_path, ec));
  if (ec || size <= m_whole) return;
  std::ifstream in(m_path, std::ios::binary);
  in.seekg(m_whole);
  std::string tail(static_cast<size_t>(size - m_whole), '\0');
  in.read(tail.data(), static_cast<std::streamsize>(tail.size()));
  const size_t newline = tail.rfind('\n', static_cast<size_t>(in.gcount() > 0 ? in.gcount() - 1 : 0));
  const int64_t keep = m_whole + (newline == std::string::npos ? 0 : static_cast<int64_t>(newline) + 1);
  std::filesystem::resize_file(m_path, static_cast<uintmax_t>(keep), ec);
}

Status StatsSink::Finish(Simulation&, bool) {
  if (Status s = Flush(); !s) return s;
  if (m_out.is_open()) {
    m_out.close();
    if (m_out.fail()) {
      CutToWholeRows();
      return Status::Error("--stats " + ShowText(m_path) +
                           ": write failed (disk full?); the file ends at its last whole row");
    }
  }
  return Status::Ok();
}

// ---- checkpoints -----------------------------------------------------------------------------------

Status CheckpointSink::OnStart(Simulation& simulation) {
  // At whole multiples of the interval on the simulated clock (a continued run keeps the grid).
  const double every = m_options.checkpointEvery;
  m_next = (std::floor(simulation.Solver().Time() / every + 1e-9) + 1.0) * every;
  return Status::Ok();
}

Status CheckpointSink::OnStep(Simulation& simulation, const sim::StepInfo&) {
  const double time = simulation.Solver().Time();
  if (time < m_next - 1e-9) return Status::Ok();
  // The CSV first: a run continued from this checkpoint keeps the rows up to its step.
  if (m_stats) {
    if (Status s = m_stats->Flush(); !s) return s;
  }
  // The state saved to `path` (atomically, WriteStateFile), the `keep` - 1 before it moved to path.1
  // (the newest), path.2, ... first. `path` itself always holds a whole state.
  namespace fs = std::filesystem;
  const std::string& path = m_options.saveState;
  const int keep = m_options.checkpointKeep;
  std::error_code ec;
  const std::string base = fs::is_symlink(fs::symlink_status(path, ec)) ? fs::weakly_canonical(path, ec).string() : path;
  if (keep > 1 && fs::is_regular_file(base, ec)) {
    for (int k = keep - 1; k >= 2; --k) {
      const std::string older = base + "." + std::to_string(k - 1);
      if (fs::exists(older, ec)) fs::rename(older, base + "." + std::to_string(k), ec);
    }
    // A second name for the current file, so that `path` is never missing while the next is written.
    const std::string previous = base + ".1";
    fs::remove(previous, ec);
    fs::create_hard_link(base, previous, ec);
    if (ec) fs::copy_file(base, previous, fs::copy_options::overwrite_existing, ec);
  }
  if (Status s = simulation.WriteState(path, m_sceneName); !s) return Status::Error("--checkpoint-every: " + s.message());
  ++m_summary->checkpoints;
  m_summary->checkpointTime = time;
  m_next = (std::floor(time / m_options.checkpointEvery + 1e-9) + 1.0) * m_options.checkpointEvery;
  return Status::Ok();
}

// ---- the state at the end -------------------------------------------------------------------------

Status SaveStateSink::Finish(Simulation& simulation, bool) {
  m_saved = simulation.WriteState(m_options.saveState, m_sceneName);
  if (!m_saved) {
    m_saved = Status::Error("--save-state " + m_saved.message() +
                            (m_summary->checkpoints > 0
                                 ? Format(" (the last checkpoint, t = %.6g s, is there)", m_summary->checkpointTime)
                                 : ""));
    return Status::Ok();
  }
  m_summary->stateSaved = m_options.saveState;
  // The file does not record how it was made: a run from it skips the scene's settle as if it were done.
  if (m_summary->settle.stopped) {
    SPHXR_LOG_WARN("%s holds water whose settle was stopped at %.4g of %g s: a run from it starts from water that is "
                   "not at rest (settle again without --load-state to have a settled start)",
                   m_options.saveState.c_str(), m_summary->settle.time, m_settle);
  }
  return Status::Ok();
}

// ---- exports ---------------------------------------------------------------------------------------

Status ExportSink::Particles(Simulation& simulation, int64_t step) {
  simulation.Solver().Download(&m_host);
  char name[64];
  std::snprintf(name, sizeof(name), "particles_%06lld.%s", static_cast<long long>(step), m_options.exportFormat.c_str());
  const std::string path = (std::filesystem::path(m_options.outDir) / name).string();
  const ExportStamp stamp{step, simulation.Solver().Time()};
  Status s = m_options.exportFormat == "vtk" ? WriteVtk(path, m_host, stamp) : WritePly(path, m_host, stamp);
  if (s && simulation.Solver().Scene().params.diffuse > 0.0f) {  // spray, foam and bubbles beside (always PLY)
    simulation.Solver().DownloadDiffuse(&m_diffuse);
    std::snprintf(name, sizeof(name), "diffuse_%06lld.ply", static_cast<long long>(step));
    s = WriteDiffusePly((std::filesystem::path(m_options.outDir) / name).string(), m_diffuse, stamp);
  }
  if (s) ++m_summary->exports;
  m_particlesStep = step;
  return s;
}

Status ExportSink::Surface(Simulation& simulation, int64_t step) {
  const auto t0 = std::chrono::steady_clock::now();
  sim::SurfaceStats stats;
  if (Status s = simulation.Solver().ExtractSurface(m_surface.value_or(sim::SurfaceParams{}), &m_mesh, &stats); !s) {
    return Status::Error(m_options.scenePath + ": " + s.message());
  }
  m_surfaceSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  char name[64];
  std::snprintf(name, sizeof(name), "surface_%06lld.%s", static_cast<long long>(step), m_options.surfaceFormat.c_str());
  const std::string path = (std::filesystem::path(m_options.outDir) / name).string();
  const ExportStamp stamp{step, simulation.Solver().Time()};
  Status s = m_options.surfaceFormat == "obj" ? WriteSurfaceObj(path, m_mesh, stamp) : WriteSurfacePly(path, m_mesh, stamp);
  if (s) {
    ++m_summary->surfaceExports;
    m_summary->surfaceTriangles = m_mesh.TriangleCount();
  }
  m_surfaceStep = step;
  return s;
}

bool ExportSink::Reached(double interval, double time, int64_t* next) {
  // A hair of slack: a time meant to be a multiple of the interval (a start at k S) counts as one.
  const double slack = 1e-9 * interval;
  if (time + slack < static_cast<double>(*next) * interval) return false;
  *next = static_cast<int64_t>(std::floor((time + slack) / interval)) + 1;
  return true;
}

Status ExportSink::Due(Simulation& simulation) {
  const int64_t step = simulation.WholeStep();
  const double time = simulation.Solver().Time();
  const bool particles = m_options.exportEvery > 0 ? step % m_options.exportEvery == 0
                                                   : m_options.exportInterval > 0.0 &&
                                                         Reached(m_options.exportInterval, time, &m_nextParticles);
  if (particles) {
    if (Status s = Particles(simulation, step); !s) return s;
  }
  const bool surface = m_options.exportSurfaceEvery > 0
                           ? step % m_options.exportSurfaceEvery == 0
                           : m_options.exportSurfaceInterval > 0.0 &&
                                 Reached(m_options.exportSurfaceInterval, time, &m_nextSurface);
  if (surface) {
    if (Status s = Surface(simulation, step); !s) return s;
  }
  return Status::Ok();
}

Status ExportSink::OnStart(Simulation& simulation) {
  // The start is exported when its step (or time) is one of the exports' (a fresh run's step 0): a
  // continued run then writes the files the whole run writes.
  const double time = simulation.Solver().Time();
  for (auto [interval, next] : {std::pair{m_options.exportInterval, &m_nextParticles},
                                std::pair{m_options.exportSurfaceInterval, &m_nextSurface}}) {
    if (interval > 0.0) *next = static_cast<int64_t>(std::ceil(time / interval - 1e-9));
  }
  return Due(simulation);
}

Status ExportSink::OnStep(Simulation& simulation, const sim::StepInfo&) { return Due(simulation); }

Status ExportSink::Finish(Simulation& simulation, bool interrupted) {
  if (!interrupted) return Status::Ok();
  // The state reached is not lost: one more export at this step unless it was just written.
  const int64_t step = simulation.WholeStep();
  if ((m_options.exportEvery > 0 || m_options.exportInterval > 0.0) && m_particlesStep != step) {
    if (Status s = Particles(simulation, step); !s) return s;
  }
  if ((m_options.exportSurfaceEvery > 0 || m_options.exportSurfaceInterval > 0.0) && m_surfaceStep != step) {
    if (Status s = Surface(simulation, step); !s) return s;
  }
  return Status::Ok();
}

// ---- pictures --------------------------------------------------------------------------------------

Status PicturesSink::Create(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary,
                            std::unique_ptr<PicturesSink>* out) {
  std::unique_ptr<PicturesSink> sink(new PicturesSink(options, surface, summary));
  if (!options.framesDir.empty()) {
    if (Status s = MakeOutputDirectory("--frames", options.framesDir); !s) return s;
  }
  render::RenderQuality quality = render::RenderQuality::kHigh;
  render::ParseRenderQuality(options.renderQuality, &quality);
  if (Status s = OfflinePictures::Create(options.imageWidth, options.imageHeight, &sink->m_pictures, options.glDebug, quality);
      !s) {
    return Status::Error("--screenshot/--frames: " + s.message());
  }
  *out = std::move(sink);
  return Status::Ok();
}

// A picture is drawn from a snapshot, as in the window: in water mode from the extracted surface mesh
// (the scene's "surface" section), with the paddles at their poses.
Status PicturesSink::Picture(Simulation& simulation, const std::string& path) {
  const render::RenderMode mode = m_options.particleImages ? render::RenderMode::kParticles : render::RenderMode::kWater;
  SurfaceRequest surface;
  surface.enabled = mode == render::RenderMode::kWater;
  surface.params = m_surface.value_or(sim::SurfaceParams{});
  if (Status s = CaptureSnapshot(simulation.Solver(), simulation.Paddles(), surface, &m_snap); !s) {
    return Status::Error("picture: " + s.message());
  }
  m_snap.setup = simulation.Setup();
  return m_pictures->Write(MakeFrameScene(m_snap, mode), path);
}

Status PicturesSink::DueFrames(Simulation& simulation) {
  if (m_options.framesDir.empty()) return Status::Ok();
  while (simulation.Solver().Time() >= static_cast<double>(m_frameIndex) / m_options.fps - 1e-9) {
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(m_frameIndex));
    const std::string path = (std::filesystem::path(m_options.framesDir) / name).string();
    if (Status s = Picture(simulation, path); !s) return s;
    ++m_summary->frames;
    ++m_frameIndex;
  }
  return Status::Ok();
}

Status PicturesSink::OnStart(Simulation& simulation) {
  // Frame k shows the state after the first step at or past t = k / fps. A run from a state file goes on
  // with the first frame after the state's time (the earlier run drew those up to it), so continued
  // runs number and draw their frames as the whole run does.
  const double start = m_summary->startTime;
  if (start > 0.0) {
    m_frameIndex = static_cast<int64_t>(std::floor(start * m_options.fps));
    while (static_cast<double>(m_frameIndex) / m_options.fps - 1e-9 <= start) ++m_frameIndex;
  }
  m_firstFrame = m_frameIndex;
  return DueFrames(simulation);
}

Status PicturesSink::OnStep(Simulation& simulation, const sim::StepInfo&) { return DueFrames(simulation); }

Status PicturesSink::Finish(Simulation& simulation, bool) {
  if (m_summary->frames > 0) {
    const std::string ffmpeg = FindOnPath("ffmpeg");
    if (ffmpeg.empty()) {
      SPHXR_LOG_INFO("ffmpeg is not on the PATH: the frames stay a PNG sequence");
    } else {
      m_movie = (std::filesystem::path(m_options.framesDir) / "movie.mp4").string();
      // From the earliest frame of the unbroken sequence ending in this run's: a run continued into its
      // first run's directory makes the whole run's movie.
      int64_t movieStart = m_firstFrame;
      while (movieStart > 0) {
        char name[64];
        std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(movieStart - 1));
        std::error_code ec;
        if (!std::filesystem::is_regular_file(std::filesystem::path(m_options.framesDir) / name, ec)) break;
        --movieStart;
      }
      // ... and ending at this run's last frame (not at older, higher-numbered files in the directory).
      const std::string command = Format("'%s' -y -loglevel error -framerate %g -start_number %lld -i '%s/frame_%%05d.png' "
                                         "-frames:v %lld -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' '%s'",
                                         ffmpeg.c_str(), m_options.fps, static_cast<long long>(movieStart),
                                         m_options.framesDir.c_str(), static_cast<long long>(m_frameIndex - movieStart),
                                         m_movie.c_str());
      if (std::system(command.c_str()) != 0) {
        SPHXR_LOG_WARN("ffmpeg could not make %s; the PNG frames are there", m_movie.c_str());
        m_movie.clear();
      }
    }
  }
  if (!m_options.screenshotPath.empty()) {
    if (Status s = Picture(simulation, m_options.screenshotPath); !s) return s;
  }
  return Status::Ok();
}

// ---- progress --------------------------------------------------------------------------------------

Status ProgressSink::OnStart(Simulation&) {
  m_begin = std::chrono::steady_clock::now();
  return Status::Ok();
}

double ProgressSink::WallSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_begin).count();
}

Status ProgressSink::OnStep(Simulation& simulation, const sim::StepInfo&) {
  const double time = simulation.Solver().Time();
  const int64_t step = simulation.Solver().GetTotals().steps;  // this run's
  const double fraction = m_targetSteps > 0 ? static_cast<double>(step) / m_targetSteps
                                            : (time - m_startTime) / (m_targetTime - m_startTime);
  m_progress->Update(std::min(1.0, fraction), time, simulation.WholeStep(), 1e3 * WallSeconds() / step);
  return Status::Ok();
}

}  // namespace sphxr::app
