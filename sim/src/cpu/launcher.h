#pragma once
// The CPU backend's launcher (backend_cpu.cpp): the calls of launch/plain.h with the SIMD forms of the
// density, force and wall-pressure stages (cpu/stages.h) and of the solvers' neighbour passes (each in
// its solver's folder), and guided OpenMP chunks. The only place where
// the CPU's stages differ from the ones CUDA runs.
#include <thrust/iterator/counting_iterator.h>

#include "cpu/stages.h"
#include "launch/device.h"
#include "solvers/dfsph/dfsph_simd.h"  // DFSPH's factor and its solves' two passes
#include "solvers/pbf/pbf_simd.h"      // position-based fluids' lambda, correction and XSPH passes
#include "reuse_lists.h"
#include "store/fluid_store.h"

namespace sphxr::sim {

template <class Traits>
class CpuLauncher {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit CpuLauncher(DeviceOps<Traits>& device) : m_dev(device) {}

  /// The backend's counted operations (launch/device.h); this launcher's own loops count as one launch each.
  DeviceOps<Traits>& Device() { return m_dev; }
  /// The SIMD forms keep each listed pair's kernel gradient lane-blocked (PairCacheStride) for the passes
  /// after them: PBF's lambda pass for its correction (solvers/pbf/pbf_simd.h), DFSPH's factor for its solves
  /// (solvers/dfsph/dfsph_simd.h).
  static constexpr bool kPairCache = true;
  /// The SIMD stages' loop. thrust's OpenMP for_each gives each thread one equal slice; these stages'
  /// items cost what their neighbours and walls cost, and with reuse the compacted list puts the calm
  /// (skipped) water in one part of the index range, so one thread waited for the other at every stage.
  /// Guided chunks (libgomp: the remaining items over the thread count, so half the range first on 2
  /// threads, then a quarter, ... down to `chunk` items) let the thread that finishes first take over the
  /// rest (4-10 % faster than the equal slices, docs/design/simd_stages.md). An item writes only its own
  /// results, so the schedule changes no number.
  /// A stage with a SIMD form (SimdForm, solvers/pbf/pbf_simd.h) runs that form.
  template <class F>
  void ForEach(int n, int chunk, const F& f) {
    if constexpr (requires { typename SimdForm<F>::type; }) {
      Loop(n, chunk, typename SimdForm<F>::type{f});
    } else {
      Loop(n, chunk, f);
    }
  }
  /// Whether the host launches the work that the flag `gate` (1: run) gates (nullptr: always): the flag
  /// is in host memory, so it is read here and the gated work is skipped entirely where it is 0.
  bool Launches(const int* gate) const { return gate == nullptr || *gate != 0; }
  /// On the calling thread: a few dozen probes are tens of microseconds of work, and a parallel region
  /// for them cost more than that on a loaded machine (sphxr_bench_probes).
  template <class F>
  void Few(int n, const F& f) {
    if (n <= 0) return;
    m_dev.Counter().Launch();
    for (int k = 0; k < n; ++k) f(k);
  }
  /// kLanes wall particles of a cell at once (cpu/walls.h).
  void WallPressure(const WallPressureStage& stage, int cells) { ForEach(cells, 8, WallPressureBlockStage{stage}); }

  /// Density in blocks of cells (cpu/density.h), drawn from every particle or, with reuse, from the
  /// compacted list, so that the particles that reuse take no lane (cpu/blocks.h BlockSet). The
  /// pairs-only layout (UsePairDensityBlocks) keeps the layout before both: every particle, the lanes
  /// that reuse masked.
  void Density(const DensityStage& density, FluidStore<Traits>& store, ReuseLists<Traits>& reuse, const Physics& ph,
               int computing, const uint32_t* /*list*/) {
    const int n = density.fluid.count;
    BlockSet set{Raw(store.Keys()), n};
    if (computing < n && !m_pairBlocks) set = reuse.template CompactedBlocks<BlockSet>(store.Keys(), density.fluid, ph, computing);
    m_dev.Resize(m_blockStart, static_cast<size_t>(set.count));
    const thrust::counting_iterator<int> first(0);
    const int blocks = m_dev.CopyIf(first, first + set.count, m_blockStart.begin(),
                                    DensityBlockStart{density.grid, set, m_pairBlocks});
    const bool masked = computing < n && m_pairBlocks;
    ForEach(blocks, 8,
            DensityBlockStage{density, set, Raw(m_blockStart), masked ? Raw(store.Idle()) : nullptr, ph.reuseIdle,
                              m_pairBlocks});
  }

  /// Forces in SIMD over each neighbour list (cpu/forces.h).
  void Forces(const ForceStage& forces, int computing, const uint32_t* list) {
    const ForceListStage stage{forces};
    if (computing < forces.fluid.count) {
      ForEach(computing, 32, OverList<ForceListStage>{list, stage});
    } else {
      ForEach(computing, 32, stage);
    }
  }

  /// The density blocks from pairs of cells only (Backend::UsePairDensityBlocks).
  void UsePairBlocks() { m_pairBlocks = true; }

 private:
  template <class F>
  void Loop(int n, int chunk, const F& f) {
    if (n <= 0) return;
    m_dev.Counter().Launch();
#pragma omp parallel for schedule(guided, chunk)
    for (int i = 0; i < n; ++i) f(i);
  }

  DeviceOps<Traits>& m_dev;
  Vector<uint32_t> m_blockStart;  // the density blocks: first entry of each (cpu/blocks.h)
  bool m_pairBlocks = false;
};

}  // namespace sphxr::sim
