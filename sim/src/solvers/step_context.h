#pragma once
// The seam between the backend and a pressure solver (docs/dev/architecture.md "One step").
//
//   backend Step:  grid (cells, sort, ranges) -> bodies (place) -> solver.Step(context) -> reduction
//
// A StepContext carries one step: dt, the physics, the grid and fluid views, and the shared stages
// over the backend's stores, each launched by the backend's launcher (launch/plain.h, or the CPU's SIMD
// forms in cpu/launcher.h), so a solver reads as a list of named stages and never asks which backend or
// which stage form it runs on. Each solver is one folder in solvers/ (its step, its stages, its
// constants, its CPU SIMD form, its rules) and one row of the solver table (solver_table.cpp); the
// factory over Traits is solvers/factory.h.
#include <chrono>
#include <functional>

#include "launch/device.h"
#include "probe_arrays.h"
#include "reuse_lists.h"
#include "sphxr/sim/solve_report.h"
#include "stages.h"
#include "store/boundary_store.h"
#include "store/fluid_store.h"

namespace sphxr::sim {

/// The backend's stores one step works on.
template <class Traits>
struct StepStores {
  FluidStore<Traits>& fluid;
  WallStore<Traits>& walls;
  BodyStore<Traits>& bodies;
  ReuseLists<Traits>& reuse;
  ProbeArrays<Traits>& probes;
  typename Traits::Launcher& launch;
  typename Traits::template Vector<float>& densityRate;  // delta_sph's d rho/dt
};

template <class Traits>
class StepContext {
 public:
  using LapFn = std::function<Status(Stage)>;
  StepContext(float dt, const Physics& physics, const GridView& grid, StepStores<Traits> stores, LapFn lap)
      : dt(dt), physics(physics), grid(grid), fluid(stores.fluid.View()), n(fluid.count), m_s(stores),
        m_lap(std::move(lap)) {}

  const float dt;
  const Physics& physics;  // what every stage shares (the solver's own constants are its own: Init)
  const GridView grid;
  const FluidView fluid;
  const int n;
  SolveReport report;  // the solver's statistics of this step (sphxr/sim/solve_report.h)
  /// The particles that compute density and forces this step (all, or after Activity the compacted list).
  int computing = 0;
  const uint32_t* computeList = nullptr;

  bool HasBodies() const { return !m_s.bodies.Empty(); }
  bool HasProbes() const { return !m_s.probes.Empty(); }
  /// Ends a timed stage (the validate hook runs here); a non-ok status stops the step.
  Status Lap(Stage stage) { return m_lap(stage); }
  NeighbourList Neighbours() { return m_s.fluid.Neighbours(physics.maxNeighbours); }
  typename Traits::Launcher& Launch() { return m_s.launch; }
  /// The backend's counted device operations (fills, sorts, reductions, copies; launch/device.h).
  DeviceOps<Traits>& Device() { return m_s.launch.Device(); }
  /// Each fluid particle's p_i / rho_i^2 for the bodies' reaction (nullptr without bodies).
  float* BodyPressureTerm() { return HasBodies() ? m_s.bodies.PressureTerm(n) : nullptr; }

  // ---- the shared stages (stages/*.h), in the order a step may use them ----------------------------
  /// Activity-based reuse (Huang et al. 2013, §3.3): classify and compact the particles that compute.
  void Activity() {
    computing = m_s.reuse.Classify(grid, fluid, physics, static_cast<int>(m_s.fluid.Cells()));
    computeList = m_s.reuse.List();
  }
  /// The walls' own pressure (walls with their own density; stages/walls.h).
  void WallPressure() {
    const auto& cells = m_s.walls.WallCells();
    if (!physics.wallDensity || cells.empty()) return;
    m_s.launch.WallPressure(WallPressureStage{grid, fluid, physics, Raw(cells), m_s.walls.PressureTerm()},
                            static_cast<int>(cells.size()));
  }
  /// rho_i = sum_j m W_ij + sum_b Psi_b W_ib, the Tait pressure and the neighbour lists (stages/density.h).
  void Density() {
    m_s.launch.Density(DensityStage{grid, fluid, Neighbours(), physics}, m_s.fluid, m_s.reuse, physics, computing,
                       computeList);
  }
  /// The neighbour lists of every particle into `lists`, within `reach`'s kernel support: the density
  /// stage with that kernel (its sums and pressures are meaningless and must be overwritten), gated by
  /// the device flag `gate` (PressureSolver::GridGate).
  void ListsWithin(const NeighbourList& lists, const Physics& reach, const int* gate) {
    m_s.launch.Density(DensityStage{grid, fluid, lists, reach, gate}, m_s.fluid, m_s.reuse, reach, n, nullptr);
  }
  /// Pressure, viscosity and gravity accelerations (stages/forces.h), with `ph`'s constants.
  void Forces(const Physics& ph) {
    m_s.launch.Forces(ForceStage{grid, fluid, Neighbours(), ph, BodyPressureTerm()}, computing, computeList);
  }
  void Forces() { Forces(physics); }
  /// The fluid's force on every body particle, from BodyPressureTerm; `gradScale`: the flat-wall
  /// gradient correction of the body's term (WCSPH's; 1 for a solver consistent with its boundary).
  /// `viscous`: with the artificial viscosity's wall term (the solvers whose force stage applied it).
  void BodyReaction(float gradScale, bool viscous = true) {
    Physics reaction = physics;
    reaction.bodyGradScale = gradScale;
    if (!viscous) reaction.soundSpeed = 0.0f;
    m_s.bodies.React(grid, fluid, reaction);
  }
  /// The pressure sensors and level gauges on the current state (probe_arrays.h).
  void Probes() { m_s.probes.Evaluate(grid, fluid, physics, m_s.launch); }
  /// Symplectic Euler with the impulse hold's kick, the contact, the clamps (stages/integrate.h).
  void Integrate() { Map(IntegrateStage{fluid, physics, dt}); }
  /// x += dt v, the contact and the clamps, for velocities and accelerations already stored.
  void Drift() { Map(DriftStage{fluid, physics, dt}); }
  /// delta_sph: rho += dt d rho/dt at the drifted state (stages/density_diffusion.h).
  void DensityDiffusion() {
    Device().Resize(m_s.densityRate, static_cast<size_t>(n));
    m_s.launch.ForEach(n, 32, DensityRateStage{grid, fluid, Neighbours(), physics, Raw(m_s.densityRate)});
    Map(DensityIntegrateStage{fluid, Raw(m_s.densityRate), dt});
  }
  /// Fluid particles out of the moving bodies at their end-of-step pose (stages/bodies.h).
  void PushOut() { m_s.bodies.PushOut(fluid, physics); }
  /// f(i) for every fluid particle, equal slices (cheap, uniform items).
  template <class F>
  void Map(const F& f) {
    Device().ForEach(n, f);
  }

 private:
  StepStores<Traits> m_s;
  LapFn m_lap;
};

/// A pressure solver: one method's step over the shared stages. The backend owns one (solvers/factory.h).
/// Whether the backend's launcher runs SIMD passes that keep a lane-blocked pair cache (the CPU's,
/// CpuLauncher::kPairCache): a solver then allocates the cache its passes share; the others recompute or
/// keep their own layout.
template <class Traits>
inline constexpr bool kLauncherPairCache = [] {
  if constexpr (requires { Traits::Launcher::kPairCache; }) return Traits::Launcher::kPairCache;
  return false;
}();

/// How many iterations of a solve the host launches between two reads of its state on the device (the
/// launcher's kSolveCheckEvery): 1 where a read costs nothing (the CPU's), more where it is a wait.
template <class Traits>
inline constexpr int kLauncherSolveCheckEvery = [] {
  if constexpr (requires { Traits::Launcher::kSolveCheckEvery; }) return Traits::Launcher::kSolveCheckEvery;
  return 1;
}();

template <class Traits>
class PressureSolver {
 public:
  virtual ~PressureSolver() = default;
  /// Computes its own constants from the scene, once (the backend's Init), and again only when the
  /// scene changes at run time (Solver::SetReuse); a solver whose stages read only Physics has none.
  virtual void Init(const SceneSetup& /*scene*/, const Physics& /*physics*/) {}
  /// One step of ctx.dt, after the grid and the bodies' placement; leaves every particle integrated
  /// (positions, velocities, accelerations with the clamp flags of stages/integrate.h).
  virtual Status Step(StepContext<Traits>& ctx) = 0;
  /// Before the step's grid, on the particles in their last order: a solver that searches its
  /// neighbours at predicted positions moves the particles there (PBF); the others do nothing.
  virtual void BeforeGrid(const FluidView& /*fluid*/, const Physics& /*physics*/, float /*dt*/) {}
  /// After BeforeGrid: the device flag (1: rebuild) that gates the step's grid, sort and the solver's
  /// own list building, for a solver whose neighbour lists last several steps (PBF's skin); the
  /// backend's launcher decides how (its Launches: the CPU reads it, the plain launcher gates each
  /// stage on the device). nullptr: the grid every step. `resorted`: the particles were re-sorted or
  /// replaced since the last step (the surface, the probes, an upload), so every kept list is stale.
  virtual const int* GridGate(bool /*resorted*/) { return nullptr; }
  /// The time the post-step stages advance by after this step: dt, or, for a solver that substeps
  /// the displayed frame, the frame at its last substep and 0 (they do not run) at the others.
  virtual float PostStepDt(float dt) { return dt; }

  /// The backend's counted device operations, for the work a solver launches outside a step's context
  /// (BeforeGrid). The backend binds them once, when it makes the solver.
  void Bind(DeviceOps<Traits>& device) { m_device = &device; }

 protected:
  DeviceOps<Traits>& Device() { return *m_device; }

 private:
  DeviceOps<Traits>* m_device = nullptr;
};

/// `if (Status s = expr; !s) return s;` for a solver's stage list.
#define SPHXR_TRY(expr)              \
  do {                               \
    if (Status s_ = (expr); !s_) return s_; \
  } while (0)

}  // namespace sphxr::sim
