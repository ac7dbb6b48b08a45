#pragma once
// Activity-based reuse on a backend's system (Traits as in backend_impl.h), step 3b: the cells' crowding
// on the impulse hold's synchronised steps, each particle's classification, and the compacted list of
// the particles that compute this step (the stages: stages/reuse.h); for the CPU's density blocks also
// that list's Morton keys and each particle's rank in it (cpu/blocks.h BlockSet). The hold's kick is
// IntegrateStage's (stages/integrate.h); docs/design/impulse_hold.md.
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>
#include <thrust/memory.h>

#include <cstdint>

#include "launch/device.h"
#include "stages/reuse.h"
#include "stages/views.h"

namespace sphxr::sim {

template <class Traits>
class ReuseLists {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit ReuseLists(DeviceOps<Traits>& device) : m_dev(device) {}

  /// Classifies the fluid's particles (ActivityStage; the crowding only on synchronised steps) and
  /// compacts those that compute this step into List(); returns their count. `cells`: the grid's cells.
  int Classify(const GridView& grid, const FluidView& fluid, const Physics& physics, int cells) {
    const thrust::counting_iterator<int> first(0);
    const int n = fluid.count;
    m_dev.Resize(m_cellCount, static_cast<size_t>(cells));
    m_dev.Resize(m_cellCrowd, static_cast<size_t>(cells));
    const int rows = grid.ny * grid.nz;
    uint32_t* count = Raw(m_cellCount);
    uint32_t* crowd = Raw(m_cellCrowd);
    if (physics.reuseSyncStep) {  // the impulse hold classifies on its schedule only
      m_dev.ForEach(cells, CellCountStage{grid, count});
      // The 27-cell sums in three passes (x, y, z), the two buffers in turn; the crowding ends in m_cellCrowd.
      m_dev.ForEach(rows, CellBoxSumStage{grid, count, crowd, 0});
      m_dev.ForEach(rows, CellBoxSumStage{grid, crowd, count, 1});
      m_dev.ForEach(rows, CellBoxSumStage{grid, count, crowd, 2});
    }
    m_dev.ForEach(n, ActivityStage{grid, fluid, physics, crowd});
    m_dev.Resize(m_computeList, static_cast<size_t>(n));
    return m_dev.CopyIf(first, first + n, m_computeList.begin(), ComputesThisStep{fluid.idle, physics.reuseIdle});
  }

  /// The particles that compute this step (Classify's), in Morton order.
  const uint32_t* List() { return Raw(m_computeList); }

  /// The CPU density blocks' entries drawn from the `computing` particles of List(), so that the
  /// particles that reuse take no lane: their Morton keys (from `keys`, every particle's, sorted) and
  /// every particle's rank among them.
  template <class BlockSet>
  BlockSet CompactedBlocks(const Vector<uint32_t>& keys, const FluidView& fluid, const Physics& physics,
                           int computing) {
    const thrust::counting_iterator<int> first(0);
    const int n = fluid.count;
    const uint32_t* list = Raw(m_computeList);
    m_dev.Resize(m_computeKeys, static_cast<size_t>(computing));
    m_dev.Gather(list, list + computing, keys.begin(), m_computeKeys.begin());
    m_dev.Resize(m_computeRank, static_cast<size_t>(n) + 1);
    const ComputesThisStep computes{fluid.idle, physics.reuseIdle};
    const auto flags = thrust::make_transform_iterator(first, ComputeFlag{computes, n});
    m_dev.ExclusiveScan(flags, flags + (n + 1), m_computeRank.begin(), 0u, thrust::plus<uint32_t>());
    return BlockSet{Raw(m_computeKeys), computing, list, Raw(m_computeRank)};
  }

 private:
  static uint32_t* Raw(Vector<uint32_t>& v) { return thrust::raw_pointer_cast(v.data()); }

  DeviceOps<Traits>& m_dev;
  Vector<uint32_t> m_computeList;  // indices of the particles that compute this step
  Vector<uint32_t> m_cellCount;    // particles (fluid and wall) in each cell; scratch of the 27-cell sums
  Vector<uint32_t> m_cellCrowd;    // particles in the 27 cells around each cell
  Vector<uint32_t> m_computeKeys;  // CPU density blocks: the compacted list's Morton keys
  Vector<uint32_t> m_computeRank;  // and the computing particles before each particle (n + 1)
};

}  // namespace sphxr::sim
