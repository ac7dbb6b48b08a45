#pragma once
// The one implementation of a step, templated on the thrust system. backend_cpu.cpp instantiates it
// with thrust's OpenMP system (built by the host compiler), backend_cuda.cu with the CUDA system
// (built by nvcc). Sorting, fills, gathers and reductions come from thrust (CCCL); nothing of that
// kind is hand-written. Include this from exactly one translation unit per system.
#include <thrust/copy.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/gather.h>
#include <thrust/sequence.h>
#include <thrust/functional.h>
#include <thrust/scan.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>

#include <chrono>
#include <type_traits>

#include "backend.h"
#include "backend_guard.h"
#include "dfsph_solver.h"
#include "probe_arrays.h"
#include "reuse_lists.h"
#include "surface_impl.h"

namespace sphxr::sim {

/// Traits: `template <class T> using Vector`, `static auto Policy()`, `static Status Sync(const char* stage)`
/// (waits for the work launched so far; CUDA: its error, naming the stage),
/// `static const char* kName`, `static bool kOnDevice` (where the surface mesh lives), `static int
/// kTraversalRun` (the surface traversal's vertices per work item).
template <class Traits>
class BackendImpl final : public Backend {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  const char* Name() const override { return Traits::kName; }

  Status Init(const GridShape& grid, const Physics& physics, const HostFluid& fluid,
              const HostBoundary& boundary) override {
    return GuardBackend(Traits::kName, "setting up the particles", [&] { return InitArrays(grid, physics, fluid, boundary); });
  }

  Status Step(float dt, const Physics& physics, StepReduction* out, double* stageSeconds,
              const StageHook& hook) override {
    m_lastStage = nullptr;
    return GuardBackend(Traits::kName, "the step", [&] { return StepStages(dt, physics, out, stageSeconds, hook); },
                        &m_lastStage);
  }

 private:
  Status InitArrays(const GridShape& grid, const Physics& physics, const HostFluid& fluid,
                    const HostBoundary& boundary) {
    // The force stage reads every wall particle's p_b/rho_b^2 under wall_density: without a reference
    // per boundary particle there would be nothing to compute it from.
    if (physics.wallDensity && boundary.invReference.size() != boundary.size()) {
      return Status::Error("walls with their own density need one reference per boundary particle "
                           "(sampling.h WallInverseReferences)");
    }
    m_shape = grid;
    const size_t cells = static_cast<size_t>(grid.Cells());
    m_fluidStart.resize(cells);
    m_fluidEnd.resize(cells);
    m_boundaryStart.resize(cells);
    m_boundaryEnd.resize(cells);
    m_boundaryNear.resize(cells);
    Upload(fluid);

    // Boundary: sort once by cell code, build its cell ranges, then its volumes.
    const int nb = static_cast<int>(boundary.size());
    Vector<Vec4> unsorted(boundary.position.begin(), boundary.position.end());
    Vector<float> unsortedAlpha(boundary.viscosity.begin(), boundary.viscosity.end());
    const bool wallDensity = physics.wallDensity;
    Vector<float> unsortedReference(boundary.invReference.begin(), boundary.invReference.end());
    m_boundary.resize(nb);
    m_boundaryAlpha.resize(nb);
    m_boundaryInvReference.resize(wallDensity ? nb : 0);
    m_boundaryPressureTerm.resize(wallDensity ? nb : 0);
    Vector<uint32_t> keys(nb), order(nb);
    thrust::fill(Traits::Policy(), m_boundaryStart.begin(), m_boundaryStart.end(), kEmptyCell);
    thrust::fill(Traits::Policy(), m_boundaryEnd.begin(), m_boundaryEnd.end(), kEmptyCell);
    if (nb > 0) {
      GridView g = View();
      thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), nb,
                         CellCodeStage{g, Raw(unsorted), Raw(keys), Raw(order)});
      thrust::stable_sort_by_key(Traits::Policy(), keys.begin(), keys.end(), order.begin());
      Vector<Vec4> sorted(nb);
      thrust::gather(Traits::Policy(), order.begin(), order.end(), unsorted.begin(), sorted.begin());
      thrust::gather(Traits::Policy(), order.begin(), order.end(), unsortedAlpha.begin(), m_boundaryAlpha.begin());
      if (wallDensity) {
        thrust::gather(Traits::Policy(), order.begin(), order.end(), unsortedReference.begin(), m_boundaryInvReference.begin());
      }
      thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), nb,
                         CellRangeStage{g, Raw(sorted), Raw(keys), Raw(m_boundaryStart), Raw(m_boundaryEnd), nb});
      g = View();
      thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), nb,
                         BoundaryVolumeStage{g, Raw(sorted), Raw(m_boundary), physics.boundaryGamma * physics.restDensity, physics.kernel});
    }
    // The cells that hold boundary particles: the walls' own pressure runs over them.
    m_wallCells.clear();
    if (wallDensity) {
      m_wallCells.resize(cells);
      const thrust::counting_iterator<uint32_t> cell(0);
      auto end = thrust::copy_if(Traits::Policy(), cell, cell + cells, m_boundaryStart.begin(), m_wallCells.begin(),
                                 NonEmptyCell{});
      m_wallCells.resize(end - m_wallCells.begin());
      m_wallCells.shrink_to_fit();  // (a vector keeps its capacity: 4 B per grid cell for the whole run)
    }
    // Which cells have boundary particles in their 27-cell neighbourhood (the walls never move).
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), static_cast<int>(cells),
                       BoundaryNearStage{View(), Raw(m_boundaryNear)});
    return Traits::Sync("setup");
  }

  Status StepStages(float dt, const Physics& physics, StepReduction* out, double* stageSeconds,
                    const StageHook& hook) {
    const int n = FluidCount();
    auto policy = Traits::Policy();
    *out = StepReduction{};
    auto clock = std::chrono::steady_clock::now();
    auto lap = [&](Stage stage) -> Status {
      if (Status s = Traits::Sync(StageName(stage)); !s) return s;
      m_lastStage = StageName(stage);
      const auto now = std::chrono::steady_clock::now();
      stageSeconds[static_cast<int>(stage)] += std::chrono::duration<double>(now - clock).count();
      Status s = hook ? hook(stage) : Status::Ok();
      clock = std::chrono::steady_clock::now();
      return s;
    };
    const thrust::counting_iterator<int> first(0);

    // 1. cell codes
    CellCodes();
    if (Status s = lap(Stage::kCells); !s) return s;

    // 2. sort by Z-order and reorder every field of the list
    SortAndReorder();
    if (Status s = lap(Stage::kSort); !s) return s;

    // 3. cell ranges
    CellRanges();
    if (Status s = lap(Stage::kGrid); !s) return s;

    // 3a. moving boundaries (paddles): place, sort, cell ranges, near-cell flags
    const bool bodies = !m_hostStates.empty();
    if (bodies) {
      PlaceBodies();
      if (Status s = lap(Stage::kBodies); !s) return s;
    }

    // 3b. activity (reuse): classify, then compact the particles that compute this step (reuse_lists.h)
    const FluidView fv = Fluid();
    int computing = n;
    const uint32_t* computeList = nullptr;  // set once the list is sized: a resize moves its storage
    if (physics.reuseEnabled) {
      computing = m_reuse.Classify(View(), fv, physics, static_cast<int>(m_fluidStart.size()));
      computeList = m_reuse.List();
      if (Status s = lap(Stage::kActivity); !s) return s;
    }

    // The per-particle and per-block loops: the CPU's SIMD stages in guided chunks of at least `chunk`
    // items (backend_cpu.cpp), every other stage one thrust::for_each_n.
    auto loop = [&](int count, int chunk, const auto& stage) {
      if constexpr (Traits::kSimdStages) {
        Traits::ForEachGuided(count, chunk, stage);
      } else {
        (void)chunk;
        thrust::for_each_n(policy, first, count, stage);
      }
    };
    // Density and forces run over every particle, or with reuse over the compacted list only:
    // skipped particles cost nothing. With every particle computing the list is 0..n-1: no indirection.
    auto overComputing = [&](int chunk, const auto& stage) {
      using S = std::decay_t<decltype(stage)>;
      if (computing < n) {
        loop(computing, chunk, OverList<S>{computeList, stage});
      } else {
        loop(n, chunk, stage);
      }
    };

    // 3c. the walls' own pressure
    if (physics.wallDensity && !m_wallCells.empty()) {
      const WallPressureStage wallPressure{View(), fv, physics, Raw(m_wallCells), Raw(m_boundaryPressureTerm)};
      const int wallCells = static_cast<int>(m_wallCells.size());
      if constexpr (Traits::kSimdStages) {  // the CPU: kLanes wall particles of a cell at once (cpu/walls.h)
        loop(wallCells, 8, typename Traits::WallPressureBlockStage{wallPressure});
      } else {
        loop(wallCells, 8, wallPressure);
      }
    }
    // 4. density and pressure. The CPU runs it in blocks of cells (cpu/density.h), with reuse drawn from
    // the compacted list; CUDA a thread per particle (over the compacted list with reuse).
    const DensityStage density{View(), fv, Neighbours(physics), physics};
    if constexpr (Traits::kSimdStages) {
      // The blocks are drawn from every particle, or with reuse from the compacted list, so that the
      // particles that reuse take no lane (cpu/blocks.h BlockSet). The pairs-only layout (benchmarks)
      // keeps the layout before both: every particle, the lanes that reuse masked.
      typename Traits::BlockSet set{Raw(m_keys), n};
      if (computing < n && !m_pairBlocks) {
        set = m_reuse.template CompactedBlocks<typename Traits::BlockSet>(m_keys, fv, physics, computing);
      }
      m_blockStart.resize(set.count);
      auto end = thrust::copy_if(policy, first, first + set.count, m_blockStart.begin(),
                                 typename Traits::DensityBlockStart{View(), set, m_pairBlocks});
      const int blocks = static_cast<int>(end - m_blockStart.begin());
      const bool masked = computing < n && m_pairBlocks;  // the pairs-only layout's masked lanes
      loop(blocks, 8,
           typename Traits::DensityBlockStage{density, set, Raw(m_blockStart), masked ? Raw(m_fluid.idle) : nullptr,
                                              physics.reuseIdle, m_pairBlocks});
    } else if (computing < n) {
      loop(computing, 32, OverList<DensityStage>{computeList, density});
    } else {
      loop(n, 32, density);
    }
    if (Status s = lap(Stage::kDensity); !s) return s;

    // DFSPH (dfsph_solver.h): the factor and kernel-gradient cache, the divergence-free solve, then the
    // force stage below with every pressure zero (viscosity and gravity only).
    if (physics.dfsph) {
      m_dfsph.Prepare(View(), fv, Neighbours(physics), physics);
      if (Status s = lap(Stage::kDensity); !s) return s;
      const auto divergence = m_dfsph.Divergence(View(), fv, Neighbours(physics), physics, dt);
      out->divergenceIterations = divergence.iterations;
      out->divergenceError = divergence.error;
      m_dfsph.ZeroPressure(fv);
      if (Status s = lap(Stage::kDivergence); !s) return s;
    }

    // 5. forces
    if (bodies && m_bodyPressureTerm.size() != static_cast<size_t>(n)) m_bodyPressureTerm.resize(n);
    const ForceStage forces{View(), fv, Neighbours(physics), physics, bodies ? Raw(m_bodyPressureTerm) : nullptr};
    if constexpr (Traits::kSimdStages) {
      overComputing(32, typename Traits::ForceListStage{forces});  // SIMD over each neighbour list (cpu/forces.h)
    } else {
      overComputing(32, forces);
    }
    if (Status s = lap(Stage::kForces); !s) return s;

    // DFSPH: v* = v + dt a, the density-invariance solve, then the step's pressure (p_i/rho_i^2 into the
    // body reaction's term), acceleration and drift.
    if (physics.dfsph) {
      m_dfsph.Kick(fv, dt);
      const auto density = m_dfsph.Density(View(), fv, Neighbours(physics), physics, dt);
      out->densityIterations = density.iterations;
      out->densityError = density.error;
      if (Status s = lap(Stage::kPressure); !s) return s;
      m_dfsph.Finish(fv, physics, dt, bodies ? Raw(m_bodyPressureTerm) : nullptr, /*drift=*/m_probes.Empty());
    }

    // 5b. the fluid's force on each body particle (the reaction). DFSPH's term is the solves' own
    // p_i/rho_i^2, without WCSPH's flat-wall gradient correction (the solve is consistent with its own
    // boundary gradients).
    if (bodies) {
      Physics reaction = physics;
      if (physics.dfsph) reaction.bodyGradScale = 1.0f;
      thrust::for_each_n(policy, first, static_cast<int>(m_bodyPos.size()),
                         BodyReactionStage{View(), fv, reaction, Raw(m_bodyPressureTerm), Raw(m_bodyForce)});
      if (Status s = lap(Stage::kBodies); !s) return s;
    }

    // 5c. probes, on the state at the start of the step (positions, grid, densities and pressures of one
    // state; DFSPH's Finish stored its pressure and leaves the drift to the stage below while probes run)
    const bool probes = !m_probes.Empty();
    if (probes) {
      EvaluateProbes(physics);
      if (Status s = lap(Stage::kProbes); !s) return s;
    }

    // 6. integrate (DFSPH drifted in its Finish, or after the probes), then the statistics the next time
    // step needs
    if (!physics.dfsph) thrust::for_each_n(policy, first, n, IntegrateStage{fv, physics, dt});
    if (physics.dfsph && probes) thrust::for_each_n(policy, first, n, DriftStage{fv, physics, dt});
    // 6a. delta_sph: rho += dt d rho/dt at the drifted state (stages/density_diffusion.h says why)
    if (physics.continuityDensity) {
      m_densityRate.resize(n);
      loop(n, 32, DensityRateStage{View(), fv, Neighbours(physics), physics, Raw(m_densityRate)});
      thrust::for_each_n(policy, first, n, DensityIntegrateStage{fv, Raw(m_densityRate), dt});
    }
    // 6b. push fluid out of the bodies at their end-of-step pose
    if (bodies) {
      if (Status s = lap(Stage::kIntegrate); !s) return s;
      thrust::for_each_n(policy, first, n,
                         PushOutStage{fv, Raw(m_bodyStates), Raw(m_shapes), static_cast<int>(m_hostStates.size()),
                                      physics.bodyClearance});
      if (Status s = lap(Stage::kBodies); !s) return s;
    }
    const StepReduction solves = *out;
    *out = thrust::transform_reduce(policy, first, first + n, StepReductionOp{fv, physics},
                                    StepReduction{}, StepReductionCombine{});
    out->computed = computing;
    out->densityIterations = solves.densityIterations;
    out->divergenceIterations = solves.divergenceIterations;
    out->densityError = solves.densityError;
    out->divergenceError = solves.divergenceError;
    return lap(Stage::kIntegrate);
  }

 public:
  void RebuildGrid(std::vector<uint32_t>* fluidStart, std::vector<uint32_t>* fluidEnd) override {
    CellCodes();
    SortAndReorder();
    CellRanges();
    fluidStart->resize(m_fluidStart.size());
    fluidEnd->resize(m_fluidEnd.size());
    thrust::copy(m_fluidStart.begin(), m_fluidStart.end(), fluidStart->begin());
    thrust::copy(m_fluidEnd.begin(), m_fluidEnd.end(), fluidEnd->begin());
  }

  void Download(HostFluid* out) const override {
    out->resize(m_fluid.position.size());
    if (out->size() == 0) return;  // (thrust's host copy of nothing dereferences a null begin: UB)
#define SPHXR_DOWNLOAD_FIELD(type, name) thrust::copy(m_fluid.name.begin(), m_fluid.name.end(), out->name.begin());
    SPHXR_FLUID_FIELDS(SPHXR_DOWNLOAD_FIELD)
#undef SPHXR_DOWNLOAD_FIELD
  }

  void DownloadBoundary(HostBoundary* out) const override {
    out->position.resize(m_boundary.size());
    thrust::copy(m_boundary.begin(), m_boundary.end(), out->position.begin());
    out->viscosity.resize(m_boundaryAlpha.size());
    thrust::copy(m_boundaryAlpha.begin(), m_boundaryAlpha.end(), out->viscosity.begin());
    out->invReference.resize(m_boundaryInvReference.size());  // empty unless the walls have their own density
    if (!out->invReference.empty()) {  // (a copy of nothing dereferences the empty vector's null begin: UB)
      thrust::copy(m_boundaryInvReference.begin(), m_boundaryInvReference.end(), out->invReference.begin());
    }
  }

  void Upload(const HostFluid& fluid) override {
    const size_t n = fluid.size();
#define SPHXR_UPLOAD_FIELD(type, name) \
  m_fluid.name.resize(n);              \
  if (n > 0) thrust::copy(fluid.name.begin(), fluid.name.end(), m_fluid.name.begin());  /* (as in Download) */
    SPHXR_FLUID_FIELDS(SPHXR_UPLOAD_FIELD)
#undef SPHXR_UPLOAD_FIELD
    m_keys.resize(n);
    m_order.resize(n);
    m_scratchVec4.resize(n);
    m_scratchFloat.resize(n);
    m_scratchU32.resize(n);
    m_scratchI32.resize(n);
  }

  FireSums FireReduce() override {
    const thrust::counting_iterator<int> first(0);
    return thrust::transform_reduce(Traits::Policy(), first, first + FluidCount(), FireSumsOp{Fluid()}, FireSums{},
                                    FireSumsCombine{});
  }

  void FireMix(float keep, float mix) override {
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), FluidCount(), FireMixStage{Fluid(), keep, mix});
  }

  void SetProbes(const std::vector<Vec4>& p, const std::vector<ProbeLine>& l) override { m_probes.Set(p, l); }
  void ProbeValues(std::vector<float>* out) const override { m_probes.Values(out); }

  void SampleProbesNow(const Physics& physics) override {
    if (m_probes.Empty()) return;
    CellCodes();
    SortAndReorder();
    CellRanges();
    EvaluateProbes(physics);
  }

  int FluidCount() const override { return static_cast<int>(m_fluid.position.size()); }
  int BoundaryCount() const override { return static_cast<int>(m_boundary.size()); }
  void UsePairDensityBlocks() override { m_pairBlocks = true; }

  SurfaceExtractor* Surface() override { return &m_surface; }

  void InitBodies(const std::vector<Vec4>& local, const std::vector<uint32_t>& bodyOf, const std::vector<float>& alpha,
                  const std::vector<ShapePrimitive>& shapes) override {
    const size_t nb = local.size();
    m_bodyLocal.assign(local.begin(), local.end());
    m_bodyOfLocal.assign(bodyOf.begin(), bodyOf.end());
    m_bodyAlpha.assign(alpha.begin(), alpha.end());
    m_shapes.assign(shapes.begin(), shapes.end());
    m_bodyKeys.resize(nb);
    m_bodyOrder.resize(nb);
    m_bodyPos.resize(nb);
    m_bodyVel.resize(nb);
    m_bodyOf.resize(nb);
    m_bodyForce.resize(nb);
    thrust::fill(m_bodyForce.begin(), m_bodyForce.end(), Vec4{});
    const size_t cells = static_cast<size_t>(m_shape.Cells());
    m_bodyStart.resize(cells);
    m_bodyEnd.resize(cells);
    m_movingNear.resize(cells);
    thrust::fill(m_movingNear.begin(), m_movingNear.end(), uint8_t{0});
  }

  void SetBodyStates(const std::vector<BodyState>& states) override {
    m_hostStates = states;
    m_bodyStates.assign(states.begin(), states.end());
  }

  void BodyLoads(std::vector<BodyLoad>* out) const override {
    out->assign(m_hostStates.size(), BodyLoad{});
    if (m_hostStates.empty()) return;
    std::vector<Vec4> force(m_bodyForce.size()), position(m_bodyPos.size());
    std::vector<uint32_t> of(m_bodyOf.size());
    thrust::copy(m_bodyForce.begin(), m_bodyForce.end(), force.begin());
    thrust::copy(m_bodyPos.begin(), m_bodyPos.end(), position.begin());
    thrust::copy(m_bodyOf.begin(), m_bodyOf.end(), of.begin());
    // Serial sums in the sorted order: the same result on every run and thread count.
    std::vector<double> sums(6 * m_hostStates.size(), 0.0);
    for (size_t b = 0; b < force.size(); ++b) {
      const uint32_t k = of[b];
      if (k >= m_hostStates.size()) continue;
      const Vec3 f = Xyz(force[b]);
      const Vec3 t = Cross(Xyz(position[b]) - m_hostStates[k].position, f);
      double* s = &sums[6 * k];
      s[0] += f.x, s[1] += f.y, s[2] += f.z, s[3] += t.x, s[4] += t.y, s[5] += t.z;
    }
    for (size_t k = 0; k < out->size(); ++k) {
      const double* s = &sums[6 * k];
      (*out)[k].force = Vec3{static_cast<float>(s[0]), static_cast<float>(s[1]), static_cast<float>(s[2])};
      (*out)[k].torque = Vec3{static_cast<float>(s[3]), static_cast<float>(s[4]), static_cast<float>(s[5])};
    }
  }

  void DownloadBodies(std::vector<Vec4>* position, std::vector<Vec4>* velocity) const override {
    position->resize(m_bodyPos.size());
    velocity->resize(m_bodyVel.size());
    if (m_bodyPos.empty()) return;  // (as in Download)
    thrust::copy(m_bodyPos.begin(), m_bodyPos.end(), position->begin());
    thrust::copy(m_bodyVel.begin(), m_bodyVel.end(), velocity->begin());
  }

 private:
  struct Fields {
#define SPHXR_DEVICE_FIELD(type, name) Vector<type> name;
    SPHXR_FLUID_FIELDS(SPHXR_DEVICE_FIELD)
#undef SPHXR_DEVICE_FIELD
  };

  template <class T>
  Vector<T>& Scratch() {
    if constexpr (std::is_same_v<T, Vec4>) return m_scratchVec4;
    else if constexpr (std::is_same_v<T, float>) return m_scratchFloat;
    else if constexpr (std::is_same_v<T, int32_t>) return m_scratchI32;
    else {
      static_assert(std::is_same_v<T, uint32_t>, "add a scratch buffer for this type");
      return m_scratchU32;
    }
  }

  void CellCodes() {
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), FluidCount(),
                       CellCodeStage{View(), Raw(m_fluid.position), Raw(m_keys), Raw(m_order)});
  }

  void SortAndReorder() {
    thrust::stable_sort_by_key(Traits::Policy(), m_keys.begin(), m_keys.end(), m_order.begin());
    Reorder();
  }

  void CellRanges() {
    const int n = FluidCount();
    thrust::fill(Traits::Policy(), m_fluidStart.begin(), m_fluidStart.end(), kEmptyCell);
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), n,
                       CellRangeStage{View(), Raw(m_fluid.position), Raw(m_keys), Raw(m_fluidStart), Raw(m_fluidEnd), n});
  }

  /// Moving boundaries at their start-of-step pose: cell codes, stable sort, world positions and rigid
  /// velocities in sorted order, cell ranges, and the near-cell flags over each body's bounding box.
  void PlaceBodies() {
    auto policy = Traits::Policy();
    const thrust::counting_iterator<int> first(0);
    const int nb = static_cast<int>(m_bodyLocal.size());
    thrust::for_each_n(policy, first, nb,
                       BodyCellStage{View(), Raw(m_bodyStates), Raw(m_bodyLocal), Raw(m_bodyOfLocal), Raw(m_bodyKeys),
                                     Raw(m_bodyOrder)});
    thrust::stable_sort_by_key(policy, m_bodyKeys.begin(), m_bodyKeys.end(), m_bodyOrder.begin());
    thrust::for_each_n(policy, first, nb,
                       BodyPlaceStage{Raw(m_bodyStates), Raw(m_bodyLocal), Raw(m_bodyOfLocal), Raw(m_bodyAlpha),
                                      Raw(m_bodyOrder), Raw(m_bodyPos), Raw(m_bodyVel), Raw(m_bodyOf)});
    thrust::fill(policy, m_bodyStart.begin(), m_bodyStart.end(), kEmptyCell);
    thrust::for_each_n(policy, first, nb,
                       CellRangeStage{View(), Raw(m_bodyPos), Raw(m_bodyKeys), Raw(m_bodyStart), Raw(m_bodyEnd), nb});
    thrust::fill(policy, m_movingNear.begin(), m_movingNear.end(), uint8_t{0});
    const GridView g = View();
    for (const BodyState& s : m_hostStates) {
      const MovingNearStage stage = MovingNearStage::Around(g, s.position, s.boundRadius, Raw(m_movingNear));
      thrust::for_each_n(policy, first, stage.Items(), stage);
    }
  }

  /// One work item per probe over the current grid (probe_arrays.h).
  void EvaluateProbes(const Physics& physics) { m_probes.Evaluate(View(), Fluid(), physics); }

  /// Applies the sort permutation to every field of the list (one gather and one O(1) swap each).
  void Reorder() {
    auto policy = Traits::Policy();
#define SPHXR_REORDER_FIELD(type, name)                                                             \
  {                                                                                                 \
    auto& scratch = Scratch<type>();                                                                \
    thrust::gather(policy, m_order.begin(), m_order.end(), m_fluid.name.begin(), scratch.begin()); \
    m_fluid.name.swap(scratch);                                                                     \
  }
    SPHXR_FLUID_FIELDS(SPHXR_REORDER_FIELD)
#undef SPHXR_REORDER_FIELD
  }

  /// The neighbour-list scratch, sized for this step's particle count and kernel.
  NeighbourList Neighbours(const Physics& physics) {
    const int capacity = physics.maxNeighbours;
    const size_t n = static_cast<size_t>(FluidCount());
    if (m_neighbourIndex.size() != n * static_cast<size_t>(capacity)) m_neighbourIndex.resize(n * capacity);
    if (m_neighbourCount.size() != n) m_neighbourCount.resize(n);
    return NeighbourList{Raw(m_neighbourIndex), Raw(m_neighbourCount), capacity};
  }

  FluidView Fluid() {
    FluidView v;
#define SPHXR_VIEW_OF(type, name) v.name = Raw(m_fluid.name);
    SPHXR_FLUID_FIELDS(SPHXR_VIEW_OF)
#undef SPHXR_VIEW_OF
    v.count = FluidCount();
    return v;
  }

  GridView View() const {
    GridView g;
    g.origin = m_shape.origin;
    g.cellSize = m_shape.cellSize;
    g.invCellSize = 1.0f / m_shape.cellSize;
    g.nx = m_shape.nx;
    g.ny = m_shape.ny;
    g.nz = m_shape.nz;
    g.fluidStart = Raw(m_fluidStart);
    g.fluidEnd = Raw(m_fluidEnd);
    g.boundaryStart = Raw(m_boundaryStart);
    g.boundaryEnd = Raw(m_boundaryEnd);
    g.boundaryNear = Raw(m_boundaryNear);
    g.boundary = Raw(m_boundary);
    g.boundaryAlpha = Raw(m_boundaryAlpha);
    g.boundaryPressureTerm = Raw(m_boundaryPressureTerm);
    g.boundaryInvReference = Raw(m_boundaryInvReference);
    g.bodyCount = static_cast<int>(m_hostStates.size());
    g.bodyStart = Raw(m_bodyStart);
    g.bodyEnd = Raw(m_bodyEnd);
    g.body = Raw(m_bodyPos);
    g.bodyVelocity = Raw(m_bodyVel);
    g.movingNear = Raw(m_movingNear);
    return g;
  }

  GridShape m_shape{};
  Fields m_fluid;
  Vector<uint32_t> m_keys, m_order;
  Vector<Vec4> m_scratchVec4;
  Vector<float> m_scratchFloat;
  Vector<uint32_t> m_scratchU32;
  Vector<int32_t> m_scratchI32;
  Vector<uint32_t> m_fluidStart, m_fluidEnd, m_boundaryStart, m_boundaryEnd;
  Vector<uint8_t> m_boundaryNear;  // per cell: a boundary particle in its 27 cells
  Vector<uint32_t> m_neighbourIndex, m_neighbourCount;
  ReuseLists<Traits> m_reuse;      // reuse: the crowding, the compacted list of the particles that compute
  Vector<uint32_t> m_blockStart;   // CPU density blocks: first entry of each (cpu/blocks.h)
  bool m_pairBlocks = false;       // CPU density blocks from pairs of cells only (UsePairDensityBlocks)
  Vector<Vec4> m_boundary;
  Vector<float> m_boundaryAlpha;
  Vector<float> m_boundaryPressureTerm;  // per boundary particle, walls with their own density only
  Vector<float> m_boundaryInvReference;
  Vector<uint32_t> m_wallCells;  // linear indices of the cells holding boundary particles
  // Moving boundaries (stages/bodies.h): canonical body-frame particles, their sorted world copies.
  Vector<Vec4> m_bodyLocal;        // body frame, w = Psi_b
  Vector<uint32_t> m_bodyOfLocal;  // body index of each canonical particle
  Vector<float> m_bodyAlpha;       // alpha of each canonical particle
  Vector<ShapePrimitive> m_shapes;
  Vector<BodyState> m_bodyStates;
  std::vector<BodyState> m_hostStates;  // empty: no bodies, no body work
  Vector<uint32_t> m_bodyKeys, m_bodyOrder, m_bodyOf;
  Vector<Vec4> m_bodyPos, m_bodyVel, m_bodyForce;  // sorted
  Vector<uint32_t> m_bodyStart, m_bodyEnd;
  Vector<uint8_t> m_movingNear;
  Vector<float> m_bodyPressureTerm;  // per fluid particle (ForceStage or DFSPH's Finish -> BodyReactionStage)
  ProbeArrays<Traits> m_probes;      // the probes and their last readings (empty: no probes)
  Vector<float> m_densityRate;       // per fluid particle, solver.density delta_sph (DensityRateStage)
  DfsphSolver<Traits> m_dfsph;       // DFSPH's arrays (sized at its first step)
  const char* m_lastStage = nullptr;  // the step's last finished stage, for an error's message
  // The surface reads the particles through a fresh grid: the integrate stage moved them after the
  // step's sort. Re-sorting here does not change the next step (its stable sort then keeps this order).
  SurfaceImpl<Traits> m_surface{[this] {
    CellCodes();
    SortAndReorder();
    CellRanges();
    return SurfaceParticles{Raw(m_fluid.position), FluidCount(), View()};
  }};
};

}  // namespace sphxr::sim
