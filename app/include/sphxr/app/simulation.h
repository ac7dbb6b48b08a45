#pragma once
// One run of a scene, under every mode: the headless runner, the desktop window's and the headset's
// simulation thread (SimWorker), the Python module, the benchmarks and the tests build it the same way
// and advance it the same way. A Simulation owns the solver, the paddles and the frame clock; outputs
// (the stats CSV, exports, pictures, checkpoints, progress, probes) are sinks attached to it, called
// after every step.
//
//   SimScene ──Create──> paddles sampled and added as bodies, Solver::Create, Restore (a state file),
//                        PaddleSystem::Attach, the paddles' saved state and the frame clock
//   AdvanceFrame(hands)  one displayed frame (1/paddleFrameRate simulated s): Step until the first step
//                        at or past the frame's end
//   Step(hands) ───────> one solver step of the current frame:
//                          the first step at or past NextFrame() begins a frame: NextFrame() moves one
//                          period on, PaddleSystem::BeginFrame(hands at that time)
//                          Solver::Step (PBF: its substeps; WCSPH, DFSPH: their CFL steps)
//                          PaddleSystem::AfterStep (the fluid's load on each paddle)
//                          every sink's OnStep
//   Finish() ──────────> every sink's Finish
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "sphxr/app/snapshot.h"
#include "sphxr/common/status.h"
#include "sphxr/interaction/hand.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct SceneFile;
struct StateFile;

/// What a run is built from: the scene without the paddles' bodies (Create samples the paddles at the
/// scene's spacing and adds them), the paddles, and the surface to extract.
struct SimScene {
  std::string name;  // the scene's name (saved in state files)
  sim::SceneSetup setup;
  std::vector<interaction::PaddleDesc> paddles;
  double paddleFrameRate = 90.0;  // Hz (simulated): the paddles get new targets this often
  SurfaceRequest surface;
  /// The scene's probes (the "probes" section), read in every step; force probes name paddles by index.
  sim::ProbeSet probes;
  /// --load-state: the fluid and clock to start from instead of the scene's (every reset of the window
  /// returns there); null: the scene's own start.
  std::shared_ptr<const StateFile> start;
};

/// The scene file's scene, with a default hand-held paddle (interaction::BladeOnHandle sized to the
/// tank) for each hand in `hands` (0 left, 1 right) that no paddle of the scene is held by.
SimScene SimSceneFromFile(const SceneFile& scene, std::initializer_list<int> hands = {});
/// The default paddle for a hand: a blade on a handle, at most 10 cm wide, narrower in a small tank.
interaction::PaddleDesc DefaultHandPaddle(const sim::SceneSetup& setup, int hand);

class Simulation;

/// An output of a run, called by the Simulation: OnStart once before the first step (after Create and
/// any settle), OnStep after every step, Finish at the end (`interrupted`: a signal stopped the run).
/// A status that is not ok stops the run with it.
class SimulationSink {
 public:
  virtual ~SimulationSink() = default;
  virtual Status OnStart(Simulation&) { return Status::Ok(); }
  virtual Status OnStep(Simulation& simulation, const sim::StepInfo& info) = 0;
  virtual Status Finish(Simulation&, bool /*interrupted*/) { return Status::Ok(); }
};

struct SimulationConfig {
  sim::SolverConfig solver;
  /// A state file that does not fit the scene is an error (`--load-state ...`); false (a reset of the
  /// window after the panel changed the spacing): a logged fallback to the scene's own start.
  bool strictStart = true;
  /// Put before the paddles' and the solver's errors (the scene's path and ": " in the headless runner).
  std::string errorPrefix;
};

class Simulation {
 public:
  static Status Create(const SimScene& scene, const SimulationConfig& config, std::unique_ptr<Simulation>* out);

  /// One displayed frame: Step with `hands` until the solver reaches the frame's end (the first step at
  /// or past NextFrame() after the frame began; called mid-frame, after single Steps, it finishes that
  /// frame). `afterStep`, when given, is called after every step: false ends the frame there (a
  /// signal, a run that ends at a time), and the next call goes on with the same frame. Errors: Step's.
  Status AdvanceFrame(const std::vector<interaction::HandInput>& hands = {},
                      const std::function<bool()>& afterStep = {});
  /// One solver step of the current frame (runs that end at a step count, the window's single step).
  /// At or past NextFrame() a frame begins first: the clock moves one period on and the paddles take
  /// `hands` (index 0 left, 1 right; poses in the simulation's world frame; their `time` set to the new
  /// NextFrame()) as their targets at that time. Then the solver's step, the paddles' loads and every
  /// sink. Errors: the solver's (--validate's named with the whole run's step after a state file), and
  /// water that became non-finite.
  Status Step(const std::vector<interaction::HandInput>& hands = {});
  /// The sinks' OnStart (call once, before the first Step) and Finish.
  Status Start();
  Status Finish(bool interrupted);
  /// Sinks are called in the order they were added; the Simulation does not own them.
  void AddSink(SimulationSink* sink) { m_sinks.push_back(sink); }

  /// The state file of this run now (state_file.h): fluid, clock, paddles and their clock, the whole
  /// run's step count.
  Status WriteState(const std::string& path, const std::string& sceneName) const;

  sim::Solver& Solver() { return *m_solver; }
  const sim::Solver& Solver() const { return *m_solver; }
  /// Null without paddles.
  interaction::PaddleSystem* Paddles() { return m_paddles.get(); }
  const interaction::PaddleSystem* Paddles() const { return m_paddles.get(); }
  const SimScene& Scene() const { return m_scene; }
  /// The scene as the solver was built from it (with the paddles' bodies).
  const sim::SceneSetup& Setup() const { return m_setup; }
  /// Restored from the scene's state file.
  bool Restored() const { return m_restored; }
  /// The state file's step count when restored from one (-1: unknown, and saved as unknown again), else 0.
  int64_t StepsBefore() const { return m_stepsBefore; }
  /// The whole run's step number (the CSV's, the exports' file names): StepsBefore (0 when unknown)
  /// plus this solver's steps.
  int64_t WholeStep() const;
  /// The frame clock: the display time the current frame ends at and the next begins at (the first step
  /// at or past it begins it). It starts at the solver's time; a state file with paddles saves it as
  /// the paddle clock and restores it.
  double NextFrame() const { return m_nextFrame; }
  /// 1/SimScene::paddleFrameRate: the displayed frame, in simulated s.
  double FramePeriod() const { return 1.0 / m_scene.paddleFrameRate; }
  /// The displayed frame's rate from the next frame on (the headset's display rate): the frame under
  /// way ends where it was planned; the next has the new period, and PBF substeps it (Solver::
  /// SetPbfFrame). Refused unless finite and in [kMinFrameRate, kMaxFrameRate] Hz.
  Status SetFrameRate(double hz);
  static constexpr double kMinFrameRate = 1.0, kMaxFrameRate = 1000.0;

 private:
  Simulation() = default;

  Status BeginFrameRate();  // a new frame takes SetFrameRate's rate

  SimScene m_scene;
  double m_pendingFrameRate = 0.0;  // Hz, SetFrameRate's, taken when the next frame begins (0: none)
  sim::SceneSetup m_setup;
  std::unique_ptr<sim::Solver> m_solver;
  std::unique_ptr<interaction::PaddleSystem> m_paddles;  // bound to m_solver (destroyed before it)
  bool m_restored = false;
  int64_t m_stepsBefore = 0;
  double m_nextFrame = 0.0;
  std::vector<SimulationSink*> m_sinks;
};

}  // namespace sphxr::app
