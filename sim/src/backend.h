#pragma once
// The interface between the Solver (host logic: validation, time step, statistics) and a backend
// (where the particle arrays live, the stages run and the method's pressure solver steps). Every
// backend is an instance of the one template in backend_impl.h.
#include <functional>
#include <memory>

#include "sphxr/common/status.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/launch_counts.h"
#include "sphxr/sim/solver.h"
#include "stages/bodies.h"
#include "stages/probes.h"
#include "stages.h"
#include "surface_extractor.h"

namespace sphxr::sim {

struct GridShape {
  Vec3 origin;
  float cellSize;
  int nx, ny, nz;
  int64_t Cells() const { return static_cast<int64_t>(nx) * ny * nz; }
};

// StageHook (sphxr/sim/solver.h): called after each stage of a step (validate mode); a non-ok status
// stops the step.

class Backend {
 public:
  virtual ~Backend() = default;
  virtual const char* Name() const = 0;
  /// Uploads particles, sorts the boundary once and computes its volumes (Akinci et al. 2012), and
  /// makes the scene's pressure solver (solvers/factory.h) with its constants (PressureSolver::Init).
  virtual Status Init(const GridShape& grid, const SceneSetup& scene, const Physics& physics, const HostFluid& fluid,
                      const HostBoundary& boundary) = 0;
  /// The pressure solver's constants again, for a scene changed at run time (Solver::SetReuse).
  virtual void InitSolver(const SceneSetup& scene, const Physics& physics) = 0;
  /// One step of size dt: the reduction over the fluid into `out`, the solver's report into `report`.
  /// Adds each stage's time to stageSeconds (nullptr: the run asked for no timings, none is taken).
  virtual Status Step(float dt, const Physics& physics, StepReduction* out, SolveReport* report,
                      double* stageSeconds, const StageHook& hook) = 0;
  /// Runs only stages 1-3 (cells, sort, grid) and copies the cell ranges out (tests).
  virtual void RebuildGrid(std::vector<uint32_t>* fluidStart, std::vector<uint32_t>* fluidEnd) = 0;
  virtual void Download(HostFluid* out) const = 0;
  virtual void DownloadBoundary(HostBoundary* out) const = 0;
  virtual void Upload(const HostFluid& fluid) = 0;
  /// FIRE's sums over the fluid after a step (stages.h FireSumsOp), and its velocity mixing v <- keep v + mix a.
  virtual FireSums FireReduce() = 0;
  virtual void FireMix(float keep, float mix) = 0;
  virtual int FluidCount() const = 0;
  virtual int BoundaryCount() const = 0;

  // Moving boundaries (stages/bodies.h). Without InitBodies a step has no body work at all.
  /// Body-frame particles (w = Psi_b), the body of each, its alpha, and every body's primitives.
  virtual void InitBodies(const std::vector<Vec4>& local, const std::vector<uint32_t>& bodyOf,
                          const std::vector<float>& alpha, const std::vector<ShapePrimitive>& shapes) = 0;
  /// The bodies' motion during the next Step (one state per body).
  virtual void SetBodyStates(const std::vector<BodyState>& states) = 0;
  /// Force and torque (about each body's start-of-step origin) of the fluid on each body in the last step.
  virtual void BodyLoads(std::vector<BodyLoad>* out) const = 0;
  /// World positions (w = Psi_b) and velocities (w = alpha) of the body particles in the last step.
  virtual void DownloadBodies(std::vector<Vec4>* position, std::vector<Vec4>* velocity) const = 0;
  // Probes (stages/probes.h). Without SetProbes (or with empty lists) a step has no probe work at all.
  /// The pressure sensors' points and the level gauges' lines, evaluated in every following step.
  virtual void SetProbes(const std::vector<Vec4>& points, const std::vector<ProbeLine>& lines) = 0;
  /// The probes' sums (stages/probes.h's layout) of the last evaluation: the last step's, or SampleProbesNow's.
  virtual void ProbeValues(std::vector<float>* out) const = 0;
  /// Re-grids the particles (their order changes, nothing else: the next step's stable sort finds them in
  /// order) and evaluates the probes on the current state.
  virtual void SampleProbesNow(const Physics& physics) = 0;
  /// The HPMC stages on this backend's system (surface_impl.h); building from the particles re-grids them.
  virtual SurfaceExtractor* Surface() = 0;
  // Diffuse particles (diffuse_pool.h): a post-step stage, sized at Init from physics.diffuse.
  virtual int DiffuseCount() const = 0;
  /// The pool, oldest first.
  virtual void DownloadDiffuse(HostDiffuse* out) const = 0;
  /// Replaces the pool (a restart); keeps the newest when `in` holds more than the capacity and returns
  /// how many it left out.
  virtual int UploadDiffuse(const HostDiffuse& in) = 0;
  /// The post-step stages alone, on the fluid as it is (tests: the diffuse particles over a fluid that
  /// every backend holds alike). Step runs them after every step.
  virtual Status AdvancePostSteps(float dt, const Physics& physics) = 0;
  /// The CPU backend's density blocks from pairs of cells only, drawn from every particle with the lanes
  /// that reuse masked: the layout before the fitted boxes and the compacted blocks (cpu/blocks.h,
  /// docs/design/simd_stages.md). The same bits; tests and sphxr_bench_blocks hold the two together.
  /// Before the first step. The other backends have no blocks and ignore it.
  virtual void UsePairDensityBlocks() {}
  /// What the backend asked of its device since it was made (sphxr/sim/launch_counts.h).
  virtual LaunchCounts Counts() const = 0;
};

/// The constants every stage shares, for `scene` (physics.cpp): Solver::Create makes them once, and
/// Solver::Step sets a step's own (its number, the impulse hold's schedule) on a copy. Tests that drive a
/// backend directly take theirs from here.
Physics MakePhysics(const SceneSetup& scene);

std::unique_ptr<Backend> MakeCpuBackend(int threads);
/// The CUDA backend's orchestration on the host (backend_cpu_reference.cpp): every stage the per-particle
/// form of stages.h, launched as backend_cuda.cu launches it, on thrust's OpenMP system.
std::unique_ptr<Backend> MakeCpuReferenceBackend(int threads);
/// Null when the CUDA backend is not compiled in; `*why` says so.
std::unique_ptr<Backend> MakeCudaBackend(std::string* why);
int CudaDevices();
bool CudaCompiled();

}  // namespace sphxr::sim
