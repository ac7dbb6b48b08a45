#pragma once
// The diffuse particles (spray, foam, bubbles; stages/diffuse.h) on a backend's system: a post-step stage
// (post_step.h) with a pool of fixed capacity, allocated once at set-up, and its step:
//
//   1. grid     the fluid where the step left it, sorted by cell into copies of its own (the fluid's
//               order is not touched: the next step's sort, and so the water, is the same without it)
//   2. advect   every diffuse particle classified, moved and aged; alive or not     (DiffuseAdvectStage)
//   3. spawn    around the energetic fluid particles (kinetic energy above tau_k min), the normals; for
//               those, the potentials: how many each spawns              (CellFlag, Normal, SpawnCount)
//   4. pool     prefix sums of survivors and spawns; the survivors compacted in their order, the oldest
//               retired first when the spawns would not fit; the spawns appended   (DiffuseKeepStage, Emit)
//
// With no diffuse particle and no energetic fluid particle (still water) a step costs one pass over the
// fluid's velocities. The pool is kept oldest first in one of two buffers (the compaction writes the other). Every item
// writes only its own slots and the sums are of integers, so the result is the same at every thread count
// and on every backend; the random numbers are a hash of (fluid particle id, step, draw).
#include <algorithm>

#include "launch/device.h"
#include "post_step.h"
#include "sphxr/sim/diffuse.h"
#include "stages/diffuse.h"
#include "stages/grid.h"
#include "store/raw.h"

namespace sphxr::sim {

template <class Traits>
class DiffusePool final : public PostStepStage {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit DiffusePool(DeviceOps<Traits>& device) : m_dev(device) {}

  /// Sizes the pool for the scene's capacity and the grid's cells (once; nothing when diffuse is off).
  void Init(const DiffuseConstants& c, size_t cells) {
    m_capacity = c.enabled ? c.capacity : 0;
    m_count = 0;
    if (m_capacity == 0) return;
    const size_t capacity = static_cast<size_t>(m_capacity);
    for (int b = 0; b < 2; ++b) {
      m_dev.Resize(m_position[b], capacity);
      m_dev.Resize(m_velocity[b], capacity);
    }
    m_dev.Resize(m_alive, capacity);
    m_dev.Resize(m_rank, capacity);
    m_dev.Resize(m_start, cells);
    m_dev.Resize(m_end, cells);
    m_dev.Resize(m_cellFlag, cells);
  }

  bool Active(const Physics& physics) const override { return physics.diffuse.enabled && m_capacity > 0; }
  Status Run(PostStepContext& ctx) override {
    Advance(ctx.dt, ctx.physics, ctx.grid, ctx.fluid);
    return ctx.lap(Stage::kDiffuse);
  }
  int Count() const { return m_count; }

  /// One step of the diffuse particles over `fluid` (steps 1-4 above).
  void Advance(float dt, const Physics& ph, GridView grid, const FluidView& fluid) {
    const int n = fluid.count;
    Size(n);
    // Nothing to move and no fluid particle with the kinetic energy to spawn: nothing to do (still water
    // costs one pass over the velocities).
    const DiffuseEnergetic energetic{2.0f * ph.diffuse.energyMin};
    const int energeticCount = n > 0 ? m_dev.CountIf(fluid.velocity, fluid.velocity + n, energetic) : 0;
    if (m_count == 0 && energeticCount == 0) return;
    // 1. the grid of the fluid as it is now, over copies
    if (n > 0) {
      m_dev.ForEach(n, CellCodeStage{grid, fluid.position, Raw(m_keys), Raw(m_order)});
      m_dev.SortPairs(m_keys, m_order);
      m_dev.Gather(m_order.begin(), m_order.end(), fluid.position, m_fluidPosition.begin());
      m_dev.Gather(m_order.begin(), m_order.end(), fluid.velocity, m_fluidVelocity.begin());
      m_dev.Gather(m_order.begin(), m_order.end(), fluid.id, m_fluidId.begin());
    }
    m_dev.Fill(m_start, kEmptyCell);
    if (n > 0) {
      m_dev.ForEach(n,
                         CellRangeStage{grid, Raw(m_fluidPosition), Raw(m_keys), Raw(m_start), Raw(m_end), n});
    }
    grid.fluidStart = Raw(m_start);
    grid.fluidEnd = Raw(m_end);
    const DiffuseFluidView
        view{Raw(m_fluidPosition), Raw(m_fluidVelocity), Raw(m_fluidId), Raw(m_normal), Raw(m_spawn), Raw(m_offset), n};
    // 2. the pool's particles
    const int now = m_current;
    if (m_count > 0) {
      m_dev.ForEach(m_count,
                         DiffuseAdvectStage{grid, Raw(m_fluidPosition), Raw(m_fluidVelocity), Pool(now), ph, dt});
    }
    // 3. what the fluid spawns
    uint32_t spawned = 0;
    if (energeticCount > 0) {
      m_dev.ForEach(static_cast<int>(m_start.size()),
                         DiffuseCellFlagStage{Raw(m_start), Raw(m_end), Raw(m_fluidVelocity), energetic,
                                              Raw(m_cellFlag)});
      m_dev.ForEach(n, DiffuseNormalStage{grid, view, ph, Raw(m_cellFlag)});
      m_dev.ForEach(n, DiffuseSpawnCountStage{grid, view, ph, dt});
      spawned = m_dev.ExclusiveScanTotal(m_spawn, static_cast<size_t>(n), m_offset);
    }
    uint32_t survivors = 0;
    if (m_count > 0) {
      survivors = m_dev.ExclusiveScanTotal(m_alive, static_cast<size_t>(m_count), m_rank);
    }
    // 4. the survivors in their order, less the oldest that the spawns need room from; then the spawns
    const uint32_t capacity = static_cast<uint32_t>(m_capacity);
    const uint32_t born = std::min(spawned, capacity);
    const uint32_t drop = survivors + born > capacity ? survivors + born - capacity : 0u;
    const uint32_t kept = survivors - drop;
    const int next = 1 - now;
    if (kept > 0) {
      m_dev.ForEach(m_count,
                         DiffuseKeepStage{Pool(now), Raw(m_rank), Raw(m_position[next]), Raw(m_velocity[next]), drop});
    }
    if (born > 0) m_dev.ForEach(n, DiffuseEmitStage{grid, view, Pool(next), ph, dt, kept, born});
    m_current = next;
    m_count = static_cast<int>(kept + born);
  }

  /// The pool, oldest first.
  void Download(HostDiffuse* out) const {
    out->resize(m_count);
    if (m_count == 0) return;
    const auto& position = m_position[m_current];
    const auto& velocity = m_velocity[m_current];
    m_dev.Download(position.begin(), position.begin() + m_count, out->position.begin(), /*asked=*/true);
    m_dev.Download(velocity.begin(), velocity.begin() + m_count, out->velocity.begin(), /*asked=*/true);
  }
  /// Replaces the pool (a restart): the newest `capacity` of `in` when it holds more. Returns how many
  /// of `in` were left out.
  int Upload(const HostDiffuse& in) {
    const int take = std::min(in.count, m_capacity);
    const int skip = in.count - take;
    m_current = 0;
    m_count = take;
    if (take > 0) {
      m_dev.Upload(in.position.begin() + skip, in.position.end(), m_position[0].begin());
      m_dev.Upload(in.velocity.begin() + skip, in.velocity.end(), m_velocity[0].begin());
    }
    return skip;
  }

 private:
  DiffusePoolView Pool(int buffer) {
    return DiffusePoolView{Raw(m_position[buffer]), Raw(m_velocity[buffer]), Raw(m_alive), m_count};
  }
  /// The per-fluid-particle scratch, sized for the fluid's count (once: it does not change in a run).
  void Size(int n) {
    const size_t count = static_cast<size_t>(n);
    if (m_keys.size() == count) return;
    m_dev.Resize(m_keys, count);
    m_dev.Resize(m_order, count);
    m_dev.Resize(m_fluidPosition, count);
    m_dev.Resize(m_fluidVelocity, count);
    m_dev.Resize(m_fluidId, count);
    m_dev.Resize(m_normal, count);
    m_dev.Resize(m_spawn, count);
    m_dev.Resize(m_offset, count);
  }

  DeviceOps<Traits>& m_dev;
  int m_capacity = 0;
  int m_count = 0;
  int m_current = 0;                          // the buffer that holds the pool
  Vector<Vec4> m_position[2], m_velocity[2];  // capacity each: w = lifetime left, kind
  Vector<uint32_t> m_alive, m_rank;           // capacity: alive after the advection, its prefix sum
  Vector<uint32_t> m_start, m_end;            // per cell: the sorted copies' ranges
  Vector<uint8_t> m_cellFlag;                 // per cell: holds an energetic particle (DiffuseCellFlagStage)
  // per fluid particle
  Vector<uint32_t> m_keys, m_order, m_fluidId, m_spawn, m_offset;
  Vector<Vec4> m_fluidPosition, m_fluidVelocity, m_normal;
};

}  // namespace sphxr::sim
