#pragma once
// The SPH solver (its pressure solver chosen by solver.method: the solver table, solver_table.h) on a
// Z-ordered uniform grid (Huang et al. 2013, §3.1), with boundary particles after Akinci et al. (2012).
// One source for the CPU (OpenMP) and CUDA backends: see sim/src/stages.h for the per-particle stages
// and sim/src/backend_impl.h for the step. What a step reports: step_info.h.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "sphxr/common/assert.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/diffuse.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/launch_counts.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/probes.h"
#include "sphxr/sim/rigid.h"
#include "sphxr/sim/step_info.h"
#include "sphxr/sim/surface.h"

namespace sphxr::sim {

/// kCpuReference: the CUDA backend's step (backend_impl.h with the per-particle stages, no SIMD) on the
/// host, so that the CUDA orchestration runs wherever the tests run (docs/dev/backends.md). Slow.
enum class Device { kAuto, kCpu, kCuda, kCpuReference };
const char* DeviceName(Device device);
/// Parses "auto" | "cpu" | "cuda" | "cpu-reference".
bool ParseDevice(const std::string& text, Device* out);
/// True when the CUDA backend was compiled into this binary.
bool CudaBackendCompiled();
/// Number of CUDA devices usable (0 without a driver or without the CUDA backend).
int CudaDeviceCount();

struct SolverConfig {
  Device device = Device::kAuto;
  int threads = 0;        // CPU backends (cpu, cpu-reference): 0 = all cores
  bool validate = false;  // check every stage for non-finite values (slow)
  /// Time every stage (Totals::stageSeconds: the summary's and the panel's stage costs). On CUDA from
  /// events on the stream, read after the step; off, no stage is timed at all.
  bool stageTimes = true;
};

/// What Solver::Settle did.
struct SettleReport {
  double time = 0.0;         // s of steps taken (simulated, then discarded: the run starts at t = 0)
  int64_t steps = 0;
  float maxAccel = 0.0f;     // m/s^2, the largest |a| at the last step (gravity included; 0 at a rest state)
  double wallSeconds = 0.0;
  bool stopped = false;      // the progress callback asked to stop before `seconds`
};
/// The clock of a solver: what a restart needs besides the fluid fields (the next step's time step
/// depends on the last step's largest speed and acceleration).
struct SolverClock {
  double time = 0.0;        // s, simulated
  float lastMaxSpeed = 0.0f;  // m/s, of the last step
  float lastMaxAccel = 0.0f;  // m/s^2, of the last step
  int64_t steps = 0;          // steps taken since the run began: the impulse hold's schedule is in step with it
};

/// A moving body's motion, for a restart: where it is, the target segment it is on, and the velocities
/// of its last step (which the next step's time step depends on).
struct BodyMotionState {
  Pose pose, from, to;
  double fromTime = 0.0, toTime = 0.0;
  Vec3 velocity, angular;
};

/// Called after every step of a Settle with the simulated seconds done; returning false stops it there
/// (a caller that draws a progress bar limits its own redraw rate).
using SettleProgress = std::function<bool(double done)>;

class Backend;
struct Physics;
struct BodyState;
struct StepReduction;
using StageHook = std::function<Status(Stage)>;

class Solver {
 public:
  /// Validates the scene, samples particles, and sets up the chosen backend. On error `*out` stays
  /// empty and the status says what to change.
  static Status Create(const SceneSetup& scene, const SolverConfig& config, std::unique_ptr<Solver>* out);
  ~Solver();

  /// Advances one time step. Fails when a fluid particle became non-finite (validate mode names the stage
  /// and particle; without it the step's reduction counts them), or when the time step collapses. A
  /// failed step leaves the clock and the statistics where they were; the fluid and the bodies are not
  /// rolled back (the caller stops).
  Status Step();

  /// Relaxes the water toward a rest state before a run (docs/design/settle.md): `seconds`
  /// of the solver's own steps, each followed by FIRE's velocity mixing (Bitzek et al. 2006): while the
  /// forces do work (sum a.v > 0) v <- (1 - alpha) v + alpha |v| a/|a|, with alpha falling from 0.1 by
  /// 1 % per step after five such steps in a row; when they do not, every particle stops and alpha is
  /// 0.1 again. Reuse is off meanwhile. Afterwards every velocity is zero and the clock, the step count
  /// and the totals restart at 0: the settled state replaces the start. Only before the first Step.
  Status Settle(double seconds, SettleReport* report, const SettleProgress& progress = {});

  const StepInfo& LastStep() const { return m_last; }
  const Totals& GetTotals() const { return m_totals; }
  double Time() const { return m_last.time; }
  Device ActiveDevice() const { return m_device; }
  int FluidCount() const;
  int BoundaryCount() const;
  const SceneSetup& Scene() const { return m_scene; }
  float ParticleMass() const;
  float SupportRadius() const { return m_scene.params.spacing * m_scene.params.supportFactor; }
  float SoundSpeed() const;
  SolverMethod Method() const { return m_scene.method; }
  /// Maximum stable step for the current state: WCSPH's acoustic CFL, force and viscosity conditions;
  /// DFSPH's CFL on the flow (and paddle) speed and the viscosity condition.
  float StableDt() const;

  /// Copies all fluid fields to the host (current sorted order; use `id` for identity).
  void Download(HostFluid* out) const;
  void DownloadBoundary(HostBoundary* out) const;
  // ---- diffuse particles (sphxr/sim/diffuse.h): spray, foam and bubbles, with solver.diffuse on ---------
  /// How many there are now (0 when off).
  int DiffuseCount() const;
  /// Copies them to the host, oldest first.
  void DownloadDiffuse(HostDiffuse* out) const;
  /// Replaces them (a restart, after Restore): with more than solver.diffuse_capacity, the newest are
  /// kept (logged); with solver.diffuse off, none (logged). Errors: sizes that do not match `count`, a
  /// non-finite position, lifetime or velocity, a kind that is not 0, 1 or 2.
  Status RestoreDiffuse(const HostDiffuse& diffuse);
  /// Changes the reuse parameters from the next step on (the panel, the benchmarks). Every particle
  /// starts active again (idle counts reset), so no particle reuses values from before the change.
  Status SetReuse(const ReuseParams& reuse);
  /// The frame PBF substeps (solver.pbf_frame, s) from the next step on: the displayed frame's period
  /// when the display sets it (app::Simulation). Out of pbf_frame's range: refused, nothing changes.
  Status SetPbfFrame(float seconds);
  /// Replaces the fluid state (tests, restarts). Sizes must match FluidCount().
  Status Upload(const HostFluid& fluid);
  /// The clock, for a state file (app/src/state_file.h).
  SolverClock Clock() const;
  /// A restart from a saved state: replaces every fluid field and the clock. With the scene the state
  /// was saved from, the steps that follow are the saved solver's own (bit for bit on the CPU backend,
  /// tests/sim/restore_test.cpp). Moving bodies stay where they are (the scene's start pose), at rest.
  /// Only before the first step; the step count and totals start at 0. Errors: sizes that do not match
  /// FluidCount(), a non-finite clock or position.
  Status Restore(const HostFluid& fluid, const SolverClock& clock);
  /// Neighbour-grid view for tests: cell index of a point, and the particle ranges.
  struct GridInfo {
    Vec3 origin;
    float cellSize;
    int dims[3];
  };
  GridInfo Grid() const;
  // ---- moving bodies (SceneSetup::bodies, rigid.h): kinematic, driven by targets --------------------
  int BodyCount() const { return static_cast<int>(m_bodies.size()); }
  /// The body moves from its current pose (now) to `target` at `targetTime`, position linear and rotation
  /// slerp, evaluated at every step's end; it holds `target` after that time. Each step its boundary
  /// particles carry the rigid velocity that takes them there. A target time not after Time() relocates
  /// the body at once, at rest (no velocity from the jump). Errors: bad index, non-finite values.
  Status SetBodyTarget(int body, const Pose& target, double targetTime);
  Pose BodyPose(int body) const {
    SPHXR_ASSERT(body >= 0 && body < BodyCount());
    return m_bodies[body].pose;
  }
  /// The body's whole motion (a state file), and setting it back (before the first step, like Restore).
  BodyMotionState BodyMotionOf(int body) const;
  Status SetBodyMotion(int body, const BodyMotionState& motion);
  /// Linear velocity of the body origin and angular velocity during the last step.
  Vec3 BodyVelocity(int body) const {
    SPHXR_ASSERT(body >= 0 && body < BodyCount());
    return m_bodies[body].velocity;
  }
  Vec3 BodyAngularVelocity(int body) const {
    SPHXR_ASSERT(body >= 0 && body < BodyCount());
    return m_bodies[body].angular;
  }
  /// Force and torque of the fluid on the body in the last step (zero before the first).
  const BodyLoad& LastBodyLoad(int body) const {
    SPHXR_ASSERT(body >= 0 && body < static_cast<int>(m_bodyLoads.size()));
    return m_bodyLoads[body];
  }
  /// The body's boundary particles in the last step: world positions (w = Psi) and velocities (w = alpha).
  void DownloadBodies(std::vector<Vec4>* position, std::vector<Vec4>* velocity) const;
  /// Signed distance of a world point to body `body`'s solid at its current pose (negative inside).
  float BodyDistance(int body, Vec3 point) const;

  // ---- probes (sphxr/sim/probes.h) -------------------------------------------------------------------
  /// Evaluates `probes` in every following step, on the state at the start of the step, the one whose
  /// positions, densities and pressures belong together (LastProbes). An empty set turns them off: the
  /// step then does no probe work. Errors name the probe: a point outside the tank, a gauge's line outside
  /// it, a body that does not exist.
  Status SetProbes(const ProbeSet& probes);
  const ProbeSet& Probes() const { return m_probes; }
  /// The readings of the last step, of the state at its start (time Time() - LastStep().dt; the force
  /// probes: the step's LastBodyLoad). Empty vectors before the first step with probes.
  const ProbeSample& LastProbes() const { return m_probeSample; }
  /// Evaluates `probes` on the current state (tests, tools). Re-grids the particles first, as the surface
  /// does: their order changes, no value does, and the next step is the same. Force probes read the last
  /// step's loads. Errors as SetProbes.
  Status SampleProbes(const ProbeSet& probes, ProbeSample* out);

  /// The water surface by histogram-pyramid marching cubes (docs/dev/surface.md), from the current particles.
  /// Into the solver's own mesh buffer (grown when needed, reported in stats and the log); the view is
  /// valid until the next extraction.
  Status ExtractSurface(const SurfaceParams& params, SurfaceMeshView* view, SurfaceStats* stats = nullptr);
  /// The same, copied to the host.
  Status ExtractSurface(const SurfaceParams& params, SurfaceMesh* mesh, SurfaceStats* stats = nullptr);
  /// In two phases, for a renderer that writes into its own (mapped) buffer, neither reading anything
  /// back nor waiting: BuildSurface samples the field over the clamp box and builds the pyramid (the
  /// vertex count stays on the device); WriteSurface then fills target (device memory on the CUDA
  /// backend, host memory on the CPU), clamped to its capacity, and its indirect draw command if given.
  /// A write's count and clamp arrive in LastSurfaceWrite (a frame later on the CUDA backend): a
  /// renderer grows its buffer from there for the next frame.
  Status BuildSurface(const SurfaceParams& params, SurfaceStats* stats);
  Status WriteSurface(const SurfaceTarget& target, SurfaceStats* stats);
  SurfaceWriteReport LastSurfaceWrite() const;
  /// What the backend asked of its device since the solver was made: launches, host waits, device
  /// allocations, copies back (sphxr/sim/launch_counts.h). A frame's counts: the difference of two.
  LaunchCounts Counts() const;
  /// Access to the backend for tests and benchmarks (they include the private headers on purpose).
  Backend* BackendForTests() { return m_backend.get(); }

 private:
  Solver();
  SceneSetup m_scene;
  SolverConfig m_config;
  Device m_device = Device::kCpu;
  std::unique_ptr<Backend> m_backend;
  std::unique_ptr<Physics> m_physics;  // what every stage shares, for m_scene (MakePhysics)
  /// m_scene changed at run time (SetReuse): the shared constants and the pressure solver's own again.
  void SceneChanged();
  StepInfo m_last;
  Totals m_totals;
  int64_t m_stepBase = 0;  // steps of the run before a restore (SolverClock::steps)
  float m_maxAccel = 0.0f;
  // The motion (pose now, the target segment, the last step's velocities: BodyMotionState, which is what
  // a restart saves) and the fixed shape.
  struct BodyMotion : BodyMotionState {
    float boundRadius = 0.0f;
    std::vector<ShapePrimitive> shapes;
  };
  /// Puts `b` at `pose`, at rest, on a segment that ends at `time` (a relocation; Settle; Restore).
  static void HoldBody(BodyMotion* b, const Pose& pose, double time);
  /// Every field of `fluid` has FluidCount() entries; else an error naming the first that does not.
  Status CheckFluidSizes(const HostFluid& fluid, const char* who) const;
  std::vector<BodyMotion> m_bodies;
  std::vector<BodyLoad> m_bodyLoads;
  Pose BodyPoseAt(const BodyMotion& body, double time) const;
  float MaxBodySpeed() const;
  void InitBodies(const Physics& physics);
  ProbeSet m_probes;
  ProbeSample m_probeSample;
  std::vector<float> m_probeDry;  // per pressure probe: the Shepard sum below which it reads dry
  /// Checks `probes` and uploads its points and lines to the backend; `dry` gets the thresholds.
  Status UploadProbes(const ProbeSet& probes, std::vector<float>* dry);
  /// The backend's probe sums and the bodies' loads into `out`, as the state at `time` after `steps`.
  void ReadProbes(const ProbeSet& probes, const std::vector<float>& dry, double time, int64_t steps,
                  ProbeSample* out) const;
  void SampleProbesNow();  // the backend's re-grid and evaluation (solver.cpp: it has the step's physics)
  // ---- the step's parts (solver_step.cpp, bodies.cpp) ---------------------------------------------------
  /// The next step's size: the method's stable step, or solver.fixed_dt below it; an error when it collapsed.
  Status NextDt(float* dt);
  /// Validate mode: every particle finite at the start of the step, and after each stage (the hook).
  Status ValidateStart(int64_t stepNumber, HostFluid* host) const;
  StageHook ValidateHook(int64_t stepNumber, HostFluid* host) const;
  /// Each body's motion over the next `dt` (to the backend), and its end pose and loads after the step.
  std::vector<BodyState> StartBodyMotion(float dt);
  void EndBodyMotion(const std::vector<BodyState>& states);
  /// The step's reduction and the solver's report into m_last and m_totals.
  void RecordStep(float dt, const StepReduction& red, const SolveReport& report);
  /// Logs at most once per simulated second when the density solve stopped at its iteration cap.
  void WarnIfIterationCapped(const SolveReport& report);
  bool m_dtClampLogged = false;
  bool m_leakWarned = false;
  /// Logs once per run when the clamps exceed kLeakingClampRate, naming the wall that clamps most.
  void WarnIfWallsLeak();
  double m_iterationWarnTime = -1.0;  // simulated time of the last "iteration cap reached" warning
};

}  // namespace sphxr::sim
