#pragma once
// How a backend runs the shared stages: the plain launcher, a work item per particle (per wall cell,
// per probe) through thrust. The CUDA backend and cpu-reference use it; the CPU backend's own launcher
// (cpu/launcher.h) offers the same calls with the SIMD forms. A solver never asks which it has.
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>

#include "reuse_lists.h"
#include "stages.h"
#include "store/fluid_store.h"

namespace sphxr::sim {

template <class Traits>
class PlainLauncher {
 public:
  /// f(i) for i in [0, n): a stage whose items differ in cost (`chunk` is the CPU's hint; unused here).
  template <class F>
  void ForEach(int n, int /*chunk*/, const F& f) {
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), n, f);
  }
  /// Whether the host launches the work that the device flag `gate` (1: run) gates (nullptr: always).
  /// Always here: the gated stages read the flag on the device, so the host never waits for it.
  bool Launches(const int* /*gate*/) const { return true; }
  /// f(i) for a handful of items (the probes).
  template <class F>
  void Few(int n, const F& f) {
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), n, f);
  }
  /// The walls' own pressure, a work item per wall cell.
  void WallPressure(const WallPressureStage& stage, int cells) { ForEach(cells, 8, stage); }
  /// Density and pressure of the `computing` particles (all of them, or reuse's compacted `list`).
  void Density(const DensityStage& stage, FluidStore<Traits>&, ReuseLists<Traits>&, const Physics&, int computing,
               const uint32_t* list) {
    if (computing < stage.fluid.count) {
      ForEach(computing, 32, OverList<DensityStage>{list, stage});
    } else {
      ForEach(computing, 32, stage);
    }
  }
  /// Pressure, viscosity and gravity of the `computing` particles.
  void Forces(const ForceStage& stage, int computing, const uint32_t* list) {
    if (computing < stage.fluid.count) {
      ForEach(computing, 32, OverList<ForceStage>{list, stage});
    } else {
      ForEach(computing, 32, stage);
    }
  }
};

}  // namespace sphxr::sim
