#pragma once
// The simulation on its own thread, so the frame loop never waits on it. The worker steps the solver
// (no faster than real time), and publishes a snapshot of the particles at most ~60 times a second;
// the frame loop draws the newest snapshot with the newest camera, again and again when a step is
// slower than a frame.
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct SimSnapshot {
  sim::HostFluid fluid;
  sim::SceneSetup setup;
  sim::StepInfo last;
  int64_t steps = 0;
  double stageMs[static_cast<int>(sim::Stage::kCount)] = {};  // of the steps since the last snapshot
  double stepMs = 0.0;                                         // mean wall ms per step since the last snapshot
  double stepsPerSecond = 0.0;                                 // measured over the last half second
  double simSecondsPerWallSecond = 0.0;                        // measured over the last half second
  int fluidCount = 0, boundaryCount = 0;
};

class SimWorker {
 public:
  SimWorker(const sim::SolverConfig& config);
  ~SimWorker();

  /// Builds the solver for `setup` on the calling thread (so errors come back here), then starts the thread.
  Status Start(const sim::SceneSetup& setup);
  /// Replaces the scene (spacing, parameters, a new scene file): the worker rebuilds the solver.
  /// Errors are reported by LastError() and the old scene keeps running.
  void Reset(const sim::SceneSetup& setup);
  void SetPaused(bool paused);
  bool Paused() const { return m_paused.load(); }
  void StepOnce();
  /// Newest published state (never null after Start()).
  std::shared_ptr<const SimSnapshot> Latest() const;
  std::string LastError() const;
  void Stop();

 private:
  void Run();
  void Publish(double stageMs[], double stepMs);

  sim::SolverConfig m_config;
  std::unique_ptr<sim::Solver> m_solver;
  sim::SceneSetup m_setup;
  std::thread m_thread;
  mutable std::mutex m_mutex;
  std::condition_variable m_wake;
  std::shared_ptr<const SimSnapshot> m_latest;
  std::unique_ptr<sim::SceneSetup> m_pendingReset;
  std::string m_error;
  std::atomic<bool> m_stop{false}, m_paused{false};
  std::atomic<int> m_stepRequests{0};
  double m_rateSteps = 0.0, m_rateSim = 0.0;
};

}  // namespace sphxr::app
