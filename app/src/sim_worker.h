#pragma once
// The simulation on its own thread, so the frame loop never waits on it. The worker advances a
// Simulation (simulation.h) frame by frame (AdvanceFrame; no more than a frame ahead of real time) with
// the paddles driven by the newest hands (SetHands), and publishes a snapshot (particles, the water
// surface, the paddles' poses, the haptic amplitudes) after every frame; the frame's period is the
// scene's, or the headset's display period (SetFrameRate); the frame loop draws
// the newest snapshot with the newest camera, again and again when the simulation is slower than it.
#include <atomic>
#include <chrono>
#include <initializer_list>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "realtime_notice.h"
#include "state_paths.h"
#include "sphxr/app/simulation.h"
#include "sphxr/app/snapshot.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/status.h"
#include "sphxr/interaction/hand.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/render/interop.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

class SimWorker {
 public:
  SimWorker(const sim::SolverConfig& config);
  ~SimWorker();

  /// Builds the solver for the scene on the calling thread (so errors come back here), then starts the thread.
  Status Start(const SimScene& scene);
  Status Start(const sim::SceneSetup& setup);  // no paddles, the default surface
  /// Replaces the scene (spacing, parameters, a new scene file): the worker rebuilds the solver.
  /// Errors are reported by LastError() and the old scene keeps running.
  void Reset(const SimScene& scene);
  /// The same paddles and surface with new parameters.
  void Reset(const sim::SceneSetup& setup);
  /// The hands that drive the hand-held paddles (index 0 left, 1 right; missing or untracked hands: the
  /// paddle holds, then withdraws). The worker uses the newest hands for each frame (every
  /// 1/paddleFrameRate simulated s) and sets their `time` to that frame's simulated time. Poses are in
  /// the simulation's world frame; a measured velocity (hasVelocity) is taken as per simulated second.
  void SetHands(const std::vector<interaction::HandInput>& hands);
  /// The displayed frame's rate (the headset's display rate, Hz): the worker's simulation takes it at its
  /// next frame, and every scene after a reset keeps it. Not finite or out of Simulation's range: ignored.
  void SetFrameRate(double hz);
  /// Surface extraction for the snapshots (off in particle mode; the cell size from the panel).
  void SetSurface(const SurfaceRequest& surface);
  void SetPaused(bool paused);
  bool Paused() const { return m_paused.load(); }
  /// One solver step (Simulation::Step), taken even while paused.
  void StepOnce();
  /// Newest published state (never null after Start()).
  std::shared_ptr<const SimSnapshot> Latest() const;
  std::string LastError() const;
  void Stop();

  /// "save state" in the window and in --xr (the s key, the panel's button, the controller's save
  /// button): the running solver's fluid, clock and paddles (state_file.h) into `savePath`
  /// (--save-state's file), else "<scene name>.state" in the working directory, between two steps: it
  /// holds the solver lock meanwhile (a step in progress finishes first). Logged either way; returns
  /// the line the panel shows.
  std::string SaveStateLogged(const std::string& savePath, const std::string& sceneName);
  /// The same save done by the worker thread between its next two steps (paused or not), for a caller
  /// that must not wait for a step and a disk sync: the headset's frame loop. A reset asked for before
  /// it is done first. SaveMessage() then returns the line the panel shows.
  void RequestSave(const std::string& savePath, const std::string& sceneName);
  std::string SaveMessage() const;
  /// Saves that succeeded so far (either way): the headset buzzes when it grows.
  uint64_t SavesDone() const { return m_savesDone.load(); }
  /// How the water surface reaches GL: ChooseSurfacePath of the solver's device (logged once at Start),
  /// kHostCopy after FallBackToHostCopy.
  SurfacePath Path() const { return m_path.load(); }
  /// The GPU path's GL side (call on the GL thread, context current): writes the solver's newest surface
  /// (its last BuildSurface) into `*mesh` through CUDA-GL interop: grows it first (a new InteropMesh,
  /// InteropCapacity) when the last write's report says the mesh did not fit (it was clamped, or this
  /// is the first write), Maps, Solver::WriteSurface (the vertex count goes into the mesh's indirect
  /// draw command on the device; nothing is read back), Unmaps. Holds the solver lock, so the worker neither steps nor extracts meanwhile (the call
  /// waits for a step in progress). `*build` gets the build written (SimSnapshot::surfaceBuild), 0 when
  /// the solver has built none. Errors: the host-copy path, and any interop failure.
  Status WriteSurfaceInto(std::unique_ptr<render::InteropMesh>* mesh, uint64_t* build);
  /// Interop failed (a GL context that is not on the CUDA device, ...): from the next snapshot on the
  /// mesh is copied to the host. Logged once.
  void FallBackToHostCopy(const std::string& why);
  /// Tests: the interop path's bookkeeping and its fallback on a machine without a GPU (there every Map
  /// fails, as on a machine whose GL context is not on the CUDA device). The next snapshot extracts anew.
  void ForceSurfacePathForTests(SurfacePath path);

 private:
  struct Pacing;  // the worker thread's clocks (sim_worker.cpp)
  std::unique_lock<std::mutex> LockSolver();
  /// The worker thread: a pending reset, a pending save, then a frame when it is due (or the window's
  /// single step), and a snapshot after it.
  void Run();
  void ApplyPendingReset(Pacing* pacing);
  void SaveIfAsked();
  /// A frame (Simulation::AdvanceFrame) with the newest hands, or one step (`oneStep`: StepOnce).
  void AdvanceWithNewestHands(bool oneStep);
  void PublishNow(Pacing* pacing);
  void Publish(double stageMs[], double stepMs);
  /// Builds the Simulation for `scene` with the worker's solver configuration. `strict` (the first
  /// build): a state file that does not fit is an error; on a reset it is a logged fallback to the
  /// scene's own start.
  Status Build(const SimScene& scene, bool strict, std::unique_ptr<Simulation>* out) const;

  sim::SolverConfig m_config;
  std::unique_ptr<Simulation> m_sim;
  ProbeHistory m_probes;  // the worker's thread only: the probes' plots, copied into each snapshot
  SimScene m_scene;
  std::thread m_thread;
  mutable std::mutex m_mutex;
  std::condition_variable m_wake;
  std::shared_ptr<const SimSnapshot> m_latest;
  std::unique_ptr<SimScene> m_pendingReset;
  std::unique_ptr<std::pair<std::string, std::string>> m_pendingSave;  // path option, scene name; by m_mutex
  std::string m_saveMessage;                                            // guarded by m_mutex
  std::atomic<uint64_t> m_savesDone{0};
  std::vector<interaction::HandInput> m_hands;  // guarded by m_mutex
  SurfaceRequest m_surface;                     // guarded by m_mutex
  bool m_surfaceChanged = false;                // guarded by m_mutex
  std::string m_error;
  std::atomic<bool> m_stop{false}, m_paused{false};
  std::atomic<int> m_stepRequests{0};
  double m_rateSteps = 0.0, m_rateSim = 0.0;
  double m_frameRate = 0.0;  // SetFrameRate's (under m_mutex); 0: the scene's
  double m_frameRateSet = 0.0;  // the rate given to the worker's simulation (the worker thread's)
  std::unique_ptr<RealTimeNotice> m_notice;  // the worker thread's: the line when real time is out of reach
  RealTimeNotice& RealTimeNoticeOf(const sim::Solver& solver);
  std::chrono::steady_clock::time_point m_lastSurface{};
  // The solver lock: the worker holds it while it steps, extracts or replaces the solver; the GL thread
  // while it writes the surface (WriteSurfaceInto). Pending writers go first (LockSolver).
  std::mutex m_solverMutex;
  std::atomic<int> m_surfaceWriters{0};
  std::atomic<SurfacePath> m_path{SurfacePath::kHostCopy};
  uint64_t m_builds = 0;        // surfaces built so far (all solvers); guarded by m_solverMutex
  uint64_t m_builtBuild = 0;    // the current solver's last build on the interop path (0: none)
};

}  // namespace sphxr::app
