#pragma once
// How a backend runs the shared stages: the plain launcher, a work item per particle (per wall cell,
// per probe) through thrust. The CUDA backend and cpu-reference use it; the CPU backend's own launcher
// (cpu/launcher.h) offers the same calls with the SIMD forms. A solver never asks which it has. Every
// launch is one of the backend's counted device operations (launch/device.h).
#include "launch/device.h"
#include "reuse_lists.h"
#include "stages.h"
#include "store/fluid_store.h"

namespace sphxr::sim {

template <class Traits>
class PlainLauncher {
 public:
  explicit PlainLauncher(DeviceOps<Traits>& device) : m_dev(device) {}

  /// A solve's iterations launched between two of the host's reads of its state (DFSPH's solves): each
  /// read is a wait for the device; the iterations launched past the solve's end do nothing.
  static constexpr int kSolveCheckEvery = 4;

  /// The backend's counted device operations (fills, sorts, reductions, copies).
  DeviceOps<Traits>& Device() { return m_dev; }
  /// f(i) for i in [0, n): a stage whose items differ in cost (`chunk` is the CPU's hint; unused here).
  template <class F>
  void ForEach(int n, int /*chunk*/, const F& f) {
    m_dev.ForEach(n, f);
  }
  /// Whether the host launches the work that the device flag `gate` (1: run) gates (nullptr: always).
  /// Always here: the gated stages read the flag on the device, so the host never waits for it.
  bool Launches(const int* /*gate*/) const { return true; }
  /// f(i) for a handful of items (the probes).
  template <class F>
  void Few(int n, const F& f) {
    m_dev.ForEach(n, f);
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

 private:
  DeviceOps<Traits>& m_dev;
};

}  // namespace sphxr::sim
