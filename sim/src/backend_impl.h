#pragma once
// The backend: the particle stores, the grid, the bodies, the probes and one pressure solver on a thrust
// system. backend_cpu.cpp instantiates it with thrust's OpenMP system and the CPU's launcher,
// backend_cpu_reference.cpp and backend_cuda.cu with the plain launcher (launch/plain.h). Its step:
//
//   grid (cells, sort, ranges) -> bodies (place) -> solver.Step(context) -> reduction -> post-step stages
//
// The solver is one folder in solvers/ (the method's row of the solver table); the stages it calls are
// StepContext's (solvers/step_context.h). Sorting, fills, gathers and reductions come from thrust
// (CCCL); nothing of that kind is hand-written. Every device operation goes through the counted launch
// layer (launch/device.h), so Counts() says what a step asked of the device. Include this from exactly
// one translation unit per system.
#include <chrono>
#include <memory>
#include <utility>

#include "backend.h"
#include "backend_guard.h"
#include "diffuse_pool.h"
#include "launch/device.h"
#include "post_step.h"
#include "solvers/factory.h"
#include "surface_impl.h"

namespace sphxr::sim {

/// Traits: `template <class T> using Vector`, `static auto Policy()`, `static CountModel kCountsAs` (how
/// the launch layer counts, launch/device.h), `static Status Sync(const char* stage)`
/// (waits for the work launched so far; CUDA: its error, naming the stage), `using Launcher` (how the
/// shared stages run: launch/plain.h or cpu/launcher.h), `static const char* kName`, `static bool
/// kOnDevice` (where the surface mesh lives), `static bool kSurfaceOverParticles` (the surface lattice
/// over the particles' bounds, read back, instead of the clamp box), `static int kTraversalRun` (the surface traversal's
/// vertices per work item).
template <class Traits>
class BackendImpl : public Backend {  // (the CPU backend adds its team, backend_cpu.cpp)
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  BackendImpl() {
    // The surface counts its own work through the same counter when it takes the launch layer.
    if constexpr (requires(SurfaceImpl<Traits>& s, DeviceOps<Traits>& d) { s.UseDevice(d); }) {
      m_surface.UseDevice(m_device);
    }
  }

  const char* Name() const override { return Traits::kName; }

  Status Init(const GridShape& grid, const SceneSetup& scene, const Physics& physics, const HostFluid& fluid,
              const HostBoundary& boundary) override {
    return GuardBackend(Traits::kName, "setting up the particles", [&] {
      m_shape = grid;
      m_solver = MakePressureSolver<Traits>(scene.method);
      m_solver->Bind(m_device);
      m_solver->Init(scene, physics);
      m_fluid.SizeCells(static_cast<size_t>(grid.Cells()));
      m_fluid.Upload(fluid);
      if (Status s = m_walls.Init(boundary, physics, static_cast<size_t>(grid.Cells()), [this] { return View(); }); !s) {
        return s;
      }
      m_diffuse.Init(physics.diffuse, static_cast<size_t>(grid.Cells()));
      return Traits::Sync("setup");
    });
  }

  void InitSolver(const SceneSetup& scene, const Physics& physics) override { m_solver->Init(scene, physics); }

  Status Step(float dt, const Physics& physics, StepReduction* out, SolveReport* report, double* stageSeconds,
              const StageHook& hook) override {
    m_lastStage = nullptr;
    return GuardBackend(
        Traits::kName, "the step", [&] { return StepStages(dt, physics, out, report, stageSeconds, hook); },
        &m_lastStage);
  }

  void RebuildGrid(std::vector<uint32_t>* fluidStart, std::vector<uint32_t>* fluidEnd) override {
    m_fluid.Regrid(View());
    m_resorted = true;
    fluidStart->resize(m_fluid.Cells());
    fluidEnd->resize(m_fluid.Cells());
    const auto& start = m_fluid.StartVector();
    const auto& end = m_fluid.EndVector();
    m_device.Download(start.begin(), start.end(), fluidStart->begin(), /*asked=*/true);
    m_device.Download(end.begin(), end.end(), fluidEnd->begin(), /*asked=*/true);
  }

  void Download(HostFluid* out) const override { m_fluid.Download(out); }
  void DownloadBoundary(HostBoundary* out) const override { m_walls.Download(out); }
  void Upload(const HostFluid& fluid) override {
    m_fluid.Upload(fluid);
    m_resorted = true;
  }

  FireSums FireReduce() override {
    return m_device.TransformReduce(FluidCount(), FireSumsOp{m_fluid.View()}, FireSums{}, FireSumsCombine{});
  }
  void FireMix(float keep, float mix) override {
    m_device.ForEach(FluidCount(), FireMixStage{m_fluid.View(), keep, mix});
  }

  void SetProbes(const std::vector<Vec4>& p, const std::vector<ProbeLine>& l) override { m_probes.Set(p, l); }
  void ProbeValues(std::vector<float>* out) const override { m_probes.Values(out); }
  void SampleProbesNow(const Physics& physics) override {
    if (m_probes.Empty()) return;
    m_fluid.Regrid(View());
    m_resorted = true;
    m_probes.Evaluate(View(), m_fluid.View(), physics, m_launch);
  }

  int FluidCount() const override { return m_fluid.Count(); }
  int BoundaryCount() const override { return m_walls.Count(); }
  void UsePairDensityBlocks() override {
    if constexpr (requires { m_launch.UsePairBlocks(); }) m_launch.UsePairBlocks();
  }
  SurfaceExtractor* Surface() override { return &m_surface; }
  LaunchCounts Counts() const override { return m_device.Counts(); }
  int DiffuseCount() const override { return m_diffuse.Count(); }
  void DownloadDiffuse(HostDiffuse* out) const override { m_diffuse.Download(out); }
  int UploadDiffuse(const HostDiffuse& in) override { return m_diffuse.Upload(in); }
  Status AdvancePostSteps(float dt, const Physics& physics) override {
    return GuardBackend(Traits::kName, "the post-step stages", [&] {
      return PostSteps(dt, physics, [](Stage stage) { return Traits::Sync(StageName(stage)); });
    });
  }

  void InitBodies(const std::vector<Vec4>& local, const std::vector<uint32_t>& bodyOf, const std::vector<float>& alpha,
                  const std::vector<ShapePrimitive>& shapes) override {
    m_bodies.Init(local, bodyOf, alpha, shapes, static_cast<size_t>(m_shape.Cells()));
  }
  void SetBodyStates(const std::vector<BodyState>& states) override { m_bodies.SetStates(states); }
  void BodyLoads(std::vector<BodyLoad>* out) const override { m_bodies.Loads(out); }
  void DownloadBodies(std::vector<Vec4>* position, std::vector<Vec4>* velocity) const override {
    m_bodies.Download(position, velocity);
  }

 private:
  Status StepStages(float dt, const Physics& physics, StepReduction* out, SolveReport* report, double* stageSeconds,
                    const StageHook& hook) {
    // Each stage ends with a lap: a launch error is named there; its time is taken only when the run
    // asks for timings (stageSeconds), and the validate hook's host work is left out of it.
    m_clock.Start(stageSeconds);
    auto lap = [&](Stage stage) -> Status {
      SPHXR_TRY(m_clock.Lap(stage));
      m_lastStage = StageName(stage);
      if (!hook) return Status::Ok();
      Status s = hook(stage);
      m_clock.Restart();
      return s;
    };
    m_solver->BeforeGrid(m_fluid.View(), physics, dt);
    // 1. the grid: cell codes, the Z-order sort of every field, the cells' ranges (Huang et al. 2013, §3.1);
    //    gated where the solver's lists last several steps (PressureSolver::GridGate)
    const int* gate = m_solver->GridGate(std::exchange(m_resorted, false));
    if (m_launch.Launches(gate)) {
      m_fluid.CellCodes(View(), gate);
      SPHXR_TRY(lap(Stage::kCells));
      m_fluid.Sort();
      SPHXR_TRY(lap(Stage::kSort));
      m_fluid.CellRanges(View());
      SPHXR_TRY(lap(Stage::kGrid));
    }
    // 2. the moving bodies at their start-of-step pose
    if (!m_bodies.Empty()) {
      m_bodies.Place(View());
      SPHXR_TRY(lap(Stage::kBodies));
    }
    // 3. the pressure solver's step (solvers/)
    StepContext<Traits> ctx(dt, physics, View(),
                            StepStores<Traits>{m_fluid, m_walls, m_bodies, m_reuse, m_probes, m_launch, m_densityRate},
                            lap);
    SPHXR_TRY(m_solver->Step(ctx));
    // 4. the statistics the next time step needs, and the solver's own
    *out = m_device.TransformReduce(ctx.n, StepReductionOp{ctx.fluid, physics}, StepReduction{},
                                    StepReductionCombine{});
    out->computed = ctx.computing;
    *report = ctx.report;
    SPHXR_TRY(lap(Stage::kIntegrate));
    // 5. the post-step stages, on the state the step ends in (they read the fluid, never write it)
    const float postDt = m_solver->PostStepDt(dt);
    if (postDt > 0.0f) SPHXR_TRY(PostSteps(postDt, physics, lap));
    if (m_clock.Finish()) m_device.Sync();  // the stage timings' events
    return Status::Ok();
  }

  /// The post-step stages (post_step.h) in their order; a new one is a member and one entry here.
  Status PostSteps(float dt, const Physics& physics, const std::function<Status(Stage)>& lap) {
    PostStepStage* const stages[] = {&m_diffuse};
    PostStepContext ctx{dt, physics, View(), m_fluid.View(), lap};
    for (PostStepStage* stage : stages) {
      if (stage->Active(physics)) SPHXR_TRY(stage->Run(ctx));
    }
    return Status::Ok();
  }

  GridView View() {
    GridView g;
    g.origin = m_shape.origin;
    g.cellSize = m_shape.cellSize;
    g.invCellSize = 1.0f / m_shape.cellSize;
    g.nx = m_shape.nx;
    g.ny = m_shape.ny;
    g.nz = m_shape.nz;
    g.fluidStart = m_fluid.Start();
    g.fluidEnd = m_fluid.End();
    m_walls.Fill(&g);
    m_bodies.Fill(&g);
    return g;
  }

  GridShape m_shape{};
  // Every device operation below, counted (launch/device.h); mutable: the const downloads count too.
  mutable DeviceOps<Traits> m_device;
  FluidStore<Traits> m_fluid{m_device};
  WallStore<Traits> m_walls{m_device};
  BodyStore<Traits> m_bodies{m_device};
  ReuseLists<Traits> m_reuse{m_device};      // reuse: the crowding, the compacted list of the particles that compute
  ProbeArrays<Traits> m_probes{m_device};    // the probes and their last readings (empty: no probes)
  Vector<float> m_densityRate;               // per fluid particle, solver.density delta_sph (DensityRateStage)
  DiffusePool<Traits> m_diffuse{m_device};   // spray, foam and bubbles: a post-step stage (capacity 0: off)
  typename Traits::Launcher m_launch{m_device};
  std::unique_ptr<PressureSolver<Traits>> m_solver;
  typename Traits::template StageClock<Traits> m_clock;  // the stage timings (launch/host_clock.h, launch/cuda.h)
  const char* m_lastStage = nullptr;  // the step's last finished stage, for an error's message
  bool m_resorted = true;  // the particles were re-sorted or replaced outside a step (GridGate's argument)
  // The surface reads the particles through a fresh grid: the integrate stage moved them after the
  // step's sort. Re-sorting here does not change the next step (its stable sort then keeps this order).
  SurfaceImpl<Traits> m_surface{[this] {
    m_fluid.Regrid(View());
    m_resorted = true;
    return SurfaceParticles{m_fluid.View().position, FluidCount(), View()};
  }, &m_device.Counter()};
};

}  // namespace sphxr::sim
