#include "sim_worker.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "interop_surface.h"  // InteropCapacity
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"

namespace sphxr::app {
namespace {
using Clock = std::chrono::steady_clock;
double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }
}  // namespace

SimWorker::SimWorker(const sim::SolverConfig& config) : m_config(config) {}

SimWorker::~SimWorker() { Stop(); }

Status SimWorker::Build(const SimScene& scene, bool strict, std::unique_ptr<Simulation>* out) const {
  SimulationConfig config;
  config.solver = m_config;
  config.strictStart = strict;
  if (Status s = Simulation::Create(scene, config, out); !s) return s;
  if ((*out)->Restored()) {
    SPHXR_LOG_INFO("started from %s at t = %.6g s", scene.start->path.c_str(), scene.start->clock.time);
  }
  return Status::Ok();
}

Status SimWorker::Start(const SimScene& scene) {
  if (Status s = Build(scene, true, &m_sim); !s) return s;
  m_probes = ProbeHistory(scene.probes, kProbePlotSeconds);
  m_path = ChooseSurfacePath(m_sim->Solver().ActiveDevice());
  if (m_path.load() == SurfacePath::kInterop) {
    LogOnce("surface-path", LogLevel::kInfo,
            "surface: solver on the CUDA device: the mesh is written into the GL buffers in place (CUDA-GL interop, "
            "no host copy)");
  } else {
    LogOnce("surface-path", LogLevel::kInfo,
            "surface: solver on the CPU: the mesh is copied into each snapshot and uploaded to GL (host path)");
  }
  {
    std::lock_guard lock(m_mutex);
    m_scene = scene;
    m_surface = scene.surface;
  }
  double zero[static_cast<int>(sim::Stage::kCount)] = {};
  Publish(zero, 0.0);
  m_thread = std::thread([this] { Run(); });
  return Status::Ok();
}

Status SimWorker::Start(const sim::SceneSetup& setup) {
  SimScene scene;
  scene.setup = setup;
  return Start(scene);
}

void SimWorker::Reset(const SimScene& scene) {
  std::lock_guard lock(m_mutex);
  m_pendingReset = std::make_unique<SimScene>(scene);
  m_wake.notify_all();
}

void SimWorker::Reset(const sim::SceneSetup& setup) {
  std::lock_guard lock(m_mutex);
  SimScene scene = m_pendingReset ? *m_pendingReset : m_scene;
  scene.setup = setup;
  scene.surface = m_surface;
  m_pendingReset = std::make_unique<SimScene>(std::move(scene));
  m_wake.notify_all();
}

void SimWorker::SetHands(const std::vector<interaction::HandInput>& hands) {
  std::lock_guard lock(m_mutex);
  m_hands = hands;
}

void SimWorker::SetFrameRate(double hz) {
  if (!(hz >= Simulation::kMinFrameRate && hz <= Simulation::kMaxFrameRate)) return;
  std::lock_guard lock(m_mutex);
  m_frameRate = hz;
}

void SimWorker::SetSurface(const SurfaceRequest& surface) {
  std::lock_guard lock(m_mutex);
  const bool changed = surface.enabled != m_surface.enabled || surface.params.cellSize != m_surface.params.cellSize ||
                       surface.params.isoLevel != m_surface.params.isoLevel ||
                       surface.params.margin != m_surface.params.margin;
  m_surface = surface;
  if (changed) m_surfaceChanged = true;
  m_wake.notify_all();
}

void SimWorker::SetPaused(bool paused) {
  m_paused = paused;
  m_wake.notify_all();
}

void SimWorker::StepOnce() {
  ++m_stepRequests;
  m_wake.notify_all();
}

std::shared_ptr<const SimSnapshot> SimWorker::Latest() const {
  std::lock_guard lock(m_mutex);
  return m_latest;
}

std::string SimWorker::LastError() const {
  std::lock_guard lock(m_mutex);
  return m_error;
}

void SimWorker::Stop() {
  m_stop = true;
  m_wake.notify_all();
  if (m_thread.joinable()) m_thread.join();
}

void SimWorker::Publish(double stageMs[], double stepMs) {
  auto snap = std::make_shared<SimSnapshot>();
  SurfaceRequest surface;
  std::shared_ptr<const SimSnapshot> previous;
  {
    std::lock_guard lock(m_mutex);
    surface = m_surface;
    previous = m_latest;
    m_surfaceChanged = false;
  }
  // The surface costs about a step or two: extracted again only when it keeps under a fifth of the
  // worker's time (or the state is about to stand still: paused, a single step, a new cell size).
  const auto now = Clock::now();
  const SurfacePath path = m_path.load();
  const bool reuseSurface = surface.enabled && previous && previous->surfaceFresh && !m_paused &&
                            previous->surfaceOnDevice == (path == SurfacePath::kInterop) &&
                            (!previous->surfaceOnDevice || previous->surfaceBuild == m_builtBuild) &&  // same solver
                            previous->surfaceCellSize > 0.0f && previous->steps > 0 &&
                            previous->surfaceMs * 5e-3 > Seconds(now - m_lastSurface) &&
                            (surface.params.cellSize <= 0.0f || surface.params.cellSize == previous->surfaceCellSize);
  SurfaceRequest request = surface;
  if (reuseSurface) request.enabled = false;
  {
    std::unique_lock solverLock = LockSolver();
    if (Status s = CaptureSnapshot(m_sim->Solver(), m_sim->Paddles(), request, snap.get(), path,
                                   ParticlesFor(path, surface));
        !s) {
      std::lock_guard lock(m_mutex);
      m_error = "surface: " + s.message();
    }
    if (snap->surfaceOnDevice) {  // built in the solver: the GL thread writes this build (WriteSurfaceInto)
      m_builtBuild = ++m_builds;
      snap->surfaceBuild = m_builtBuild;
    }
  }
  if (reuseSurface) {
    snap->surface = previous->surface;  // host path: shared copy; interop path: the solver still holds the build
    snap->surfaceOnDevice = previous->surfaceOnDevice;
    snap->surfaceVertices = previous->surfaceVertices;
    snap->surfaceBuild = previous->surfaceBuild;
    snap->surfaceMs = previous->surfaceMs;
    snap->surfaceCellSize = previous->surfaceCellSize;
    snap->surfaceFresh = false;
  } else if (request.enabled) {
    m_lastSurface = now;
  }
  snap->setup = m_scene.setup;
  snap->probes = m_probes.Traces();
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) snap->stageMs[s] = stageMs[s];
  snap->stepMs = stepMs;
  snap->stepsPerSecond = m_rateSteps;
  snap->simSecondsPerWallSecond = m_rateSim;
  std::lock_guard lock(m_mutex);
  m_latest = std::move(snap);
}

/// The worker thread's clocks: real-time pacing (simulated time may not run ahead of wall time; anchored
/// again after a pause or a reset), the half-second windows of the rates, and the totals at the last
/// snapshot (the snapshot's per-step times are over the steps since).
struct SimWorker::Pacing {
  Clock::time_point anchorWall{}, rateWindow{}, started{};
  double anchorSim = 0.0, rateSim0 = 0.0;
  int64_t rateSteps0 = 0;
  sim::Totals published;
  bool dirty = false;  // steps taken since the last snapshot

  /// Everything anchored at the solver's clock now (the start, a new solver).
  void Restart(const sim::Solver& solver) {
    anchorWall = Clock::now();
    anchorSim = solver.Time();
    published = solver.GetTotals();
    rateSteps0 = published.steps;
    rateSim0 = solver.Time();  // a state file's start is not 0
    rateWindow = Clock::now();
    started = rateWindow;
  }
};

void SimWorker::PublishNow(Pacing* p) {
  const sim::Totals& t = m_sim->Solver().GetTotals();
  const double n = std::max<double>(1.0, static_cast<double>(t.steps - p->published.steps));
  double stageMs[static_cast<int>(sim::Stage::kCount)];
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    stageMs[s] = 1e3 * (t.stageSeconds[s] - p->published.stageSeconds[s]) / n;
  }
  Publish(stageMs, 1e3 * (t.stepSeconds - p->published.stepSeconds) / n);
  p->published = t;
  p->dirty = false;
}

void SimWorker::SaveIfAsked() {
  std::unique_ptr<std::pair<std::string, std::string>> save;
  {
    std::lock_guard lock(m_mutex);
    save = std::move(m_pendingSave);
  }
  if (!save) return;
  const std::string message = SaveStateLogged(save->first, save->second);
  std::lock_guard lock(m_mutex);
  m_saveMessage = message;
}

void SimWorker::ApplyPendingReset(Pacing* pacing) {
  std::unique_ptr<SimScene> reset;
  {
    std::lock_guard lock(m_mutex);
    reset = std::move(m_pendingReset);
  }
  if (!reset) return;
  std::unique_ptr<Simulation> fresh;
  const Status s = Build(*reset, false, &fresh);
  if (!s) {
    SPHXR_LOG_WARN("scene rebuild refused: %s", s.message().c_str());
    std::lock_guard lock(m_mutex);
    m_error = s.message();
    return;
  }
  std::unique_lock solverLock = LockSolver();
  m_sim = std::move(fresh);
  m_probes = ProbeHistory(reset->probes, kProbePlotSeconds);
  m_builtBuild = 0;  // the new solver has built no surface yet
  solverLock.unlock();
  {
    std::lock_guard lock(m_mutex);  // Reset(setup) reads m_scene on the caller's thread
    m_scene = *reset;
    m_surface = m_scene.surface;
    m_error.clear();
  }
  pacing->Restart(m_sim->Solver());
  m_notice.reset();  // the new scene is judged anew
  m_frameRateSet = 0.0;  // the new simulation takes the display's rate again
  double zero[static_cast<int>(sim::Stage::kCount)] = {};
  Publish(zero, 0.0);
}

void SimWorker::AdvanceWithNewestHands(bool oneStep) {
  std::unique_lock solverLock = LockSolver();
  std::vector<interaction::HandInput> hands;  // the newest: the paddles' targets at their next frame
  double frameRate;
  {
    std::lock_guard lock(m_mutex);
    hands = m_hands;
    frameRate = m_frameRate;
  }
  // The display's rate becomes the frame's from the simulation's next frame (a change of more than 0.1 %).
  const double current = m_frameRateSet > 0.0 ? m_frameRateSet : 1.0 / m_sim->FramePeriod();
  if (frameRate > 0.0 && std::abs(frameRate / current - 1.0) > 1e-3 && m_sim->SetFrameRate(frameRate)) {
    m_frameRateSet = frameRate;
    SPHXR_LOG_INFO("frame: %.2f Hz, the display's rate (the scene's paddles.frame_rate is %g Hz)", frameRate,
                   m_scene.paddleFrameRate);
  }
  // After every step: the probes' plots, a turn for a waiting surface writer (the GL thread), and the
  // frame cut short by a pause or the end (the next frame call finishes it).
  const auto afterStep = [&] {
    m_probes.Add(m_sim->Solver().LastProbes());
    if (m_surfaceWriters.load() > 0) {
      solverLock.unlock();
      solverLock = LockSolver();
    }
    return !m_stop && !m_paused;
  };
  Status stepped;
  if (oneStep) {
    if (stepped = m_sim->Step(hands); stepped) afterStep();
  } else {
    stepped = m_sim->AdvanceFrame(hands, afterStep);
  }
  if (Status s = stepped; !s) {
    std::lock_guard lock(m_mutex);
    m_error = std::isfinite(m_sim->Solver().LastStep().maxSpeed)
                  ? s.message()
                  : "the simulation became non-finite: press reset, and lower the time step or raise the stiffness";
    m_paused = true;
  }
}

RealTimeNotice& SimWorker::RealTimeNoticeOf(const sim::Solver& solver) {
  if (!m_notice) {
    m_notice = std::make_unique<RealTimeNotice>(m_scene.name, solver.FluidCount(),
                                                sim::SolverMethodName(solver.Scene().method),
                                                sim::DeviceName(solver.ActiveDevice()), omp_get_max_threads());
  }
  return *m_notice;
}

void SimWorker::Run() {
  // The CPU backend's team size is an OpenMP setting of the thread that made the solver (Start ran on
  // the caller's thread): without this the worker's steps run with the default team, whose spinning
  // threads fight the renderer's (a software GL's above all) for the cores.
  omp_set_num_threads(m_config.threads > 0 ? m_config.threads : omp_get_num_procs());
  Pacing pacing;
  pacing.Restart(m_sim->Solver());
  while (!m_stop) {
    ApplyPendingReset(&pacing);
    SaveIfAsked();  // between two steps, after a reset asked for before it
    const bool stepRequested = m_stepRequests.load() > 0;
    bool surfaceChanged;
    {
      std::lock_guard lock(m_mutex);
      surfaceChanged = m_surfaceChanged;
    }
    if (m_paused && !stepRequested) {
      if (pacing.dirty || surfaceChanged) PublishNow(&pacing);  // the last steps before the pause are shown
      std::unique_lock lock(m_mutex);
      m_wake.wait_for(lock, std::chrono::milliseconds(20));
      pacing.anchorWall = Clock::now();
      pacing.anchorSim = m_sim->Solver().Time();
      continue;
    }
    if (!stepRequested && m_sim->Solver().Time() - pacing.anchorSim > Seconds(Clock::now() - pacing.anchorWall)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // ahead of real time
    } else {
      if (stepRequested) --m_stepRequests;
      AdvanceWithNewestHands(stepRequested);  // the window's single step, else a frame
      pacing.dirty = true;
    }
    const Clock::time_point now = Clock::now();
    if (Seconds(now - pacing.rateWindow) >= 0.5) {  // rates over half-second windows
      m_rateSteps = (m_sim->Solver().GetTotals().steps - pacing.rateSteps0) / Seconds(now - pacing.rateWindow);
      m_rateSim = (m_sim->Solver().Time() - pacing.rateSim0) / Seconds(now - pacing.rateWindow);
      pacing.rateWindow = now;
      pacing.rateSteps0 = m_sim->Solver().GetTotals().steps;
      pacing.rateSim0 = m_sim->Solver().Time();
      if (auto line = RealTimeNoticeOf(m_sim->Solver()).Observe(m_rateSim, Seconds(now - pacing.started))) {
        SPHXR_LOG_WARN("%s", line->c_str());
      }
    }
    if (pacing.dirty) PublishNow(&pacing);  // a frame (or the window's single step) taken
  }
  SaveIfAsked();  // a save asked for just before the end is not lost
}

std::unique_lock<std::mutex> SimWorker::LockSolver() {
  // std::mutex is not fair: a worker stepping back to back would take it again at once, so a waiting
  // surface writer (the GL thread, a short call) goes first.
  while (m_surfaceWriters.load() > 0) std::this_thread::yield();
  return std::unique_lock(m_solverMutex);
}

std::string SimWorker::SaveStateLogged(const std::string& savePath, const std::string& sceneName) {
  const std::string path = !savePath.empty() ? savePath : DefaultStatePath(sceneName);
  Status s;
  double t = 0.0;
  {
    ++m_surfaceWriters;  // ahead of the worker's next step, as a surface writer
    std::unique_lock solverLock(m_solverMutex);
    --m_surfaceWriters;
    t = m_sim->Solver().Time();
    s = m_sim->WriteState(path, sceneName);
  }
  if (!s) {
    SPHXR_LOG_WARN("save state: %s", s.message().c_str());
    return "save failed: " + s.message();
  }
  SPHXR_LOG_INFO("state saved to %s at t = %.6g s (sphxr --load-state %s continues from there)", path.c_str(), t,
                 path.c_str());
  ++m_savesDone;
  return Format("saved to %s (t = %.4g s): sphxr --load-state %s", path.c_str(), t, path.c_str());
}

void SimWorker::RequestSave(const std::string& savePath, const std::string& sceneName) {
  {
    std::lock_guard lock(m_mutex);
    m_pendingSave = std::make_unique<std::pair<std::string, std::string>>(savePath, sceneName);
  }
  m_wake.notify_all();
}

std::string SimWorker::SaveMessage() const {
  std::lock_guard lock(m_mutex);
  return m_saveMessage;
}

Status SimWorker::WriteSurfaceInto(std::unique_ptr<render::InteropMesh>* mesh, uint64_t* build) {
  *build = 0;
  if (m_path.load() != SurfacePath::kInterop) {
    return Status::Error("surface: the solver is on the CPU; its mesh is copied to the host, not written through interop");
  }
  ++m_surfaceWriters;
  std::unique_lock solverLock(m_solverMutex);
  --m_surfaceWriters;
  if (m_builtBuild == 0) return Status::Ok();
  const sim::SurfaceWriteReport last = m_sim->Solver().LastSurfaceWrite();
  constexpr int64_t kMaxVertices = int64_t{1} << 26;  // InteropMesh::Create's limit
  if (last.vertices > kMaxVertices) {
    return Status::Error(Format("surface: %lld vertices do not fit the interop buffers (at most %lld): raise "
                                "surface.cell_size",
                                static_cast<long long>(last.vertices), static_cast<long long>(kMaxVertices)));
  }
  const int64_t old = *mesh ? (*mesh)->Capacity() : 0;
  const int64_t grown = InteropCapacity(old, last);
  if (grown != old) {
    mesh->reset();  // unregisters the old buffers from CUDA before the new ones are made
    if (Status s = render::InteropMesh::Create(static_cast<int>(grown), mesh); !s) return s;
    SPHXR_LOG_INFO("surface: interop buffers grown from %lld to %lld vertices (%.1f MiB)%s",
                   static_cast<long long>(old), static_cast<long long>(grown), 24.0 * static_cast<double>(grown) / 1048576.0,
                   last.Clamped() ? Format(" after a mesh of %lld triangles was clamped to %lld",
                                           static_cast<long long>(last.vertices / 3),
                                           static_cast<long long>(last.written / 3)).c_str()
                                  : "");
  }
  render::InteropMesh::DevicePointers target;
  if (Status s = (*mesh)->Map(&target); !s) return s;
  sim::SurfaceStats stats;
  const Status written =
      m_sim->Solver().WriteSurface({target.positions, target.normals, target.capacity, target.drawCommand}, &stats);
  if (Status s = (*mesh)->Unmap(); !s) return s;
  if (!written) return written;
  *build = m_builtBuild;
  return Status::Ok();
}

void SimWorker::FallBackToHostCopy(const std::string& why) {
  if (m_path.exchange(SurfacePath::kHostCopy) == SurfacePath::kHostCopy) return;
  SPHXR_LOG_WARN("surface: CUDA-GL interop failed (%s); the mesh is copied to the host from now on", why.c_str());
  std::lock_guard lock(m_mutex);
  m_surfaceChanged = true;  // the next snapshot extracts a host copy at once
  m_wake.notify_all();
}

void SimWorker::ForceSurfacePathForTests(SurfacePath path) {
  m_path = path;
  std::lock_guard lock(m_mutex);
  m_surfaceChanged = true;
  m_wake.notify_all();
}

}  // namespace sphxr::app
