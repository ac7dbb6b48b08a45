#pragma once
// DensityStage (stages/density.h) in blocks of up to kLanes particles (cpu/blocks.h): each candidate
// loaded once and tested against the whole block.
#include <cstdint>

#include "cpu/blocks.h"
#include "cpu/simd.h"
#include "stages/density.h"
#include "stages/reuse.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

/// Density and pressure for the particles of block b (`blockStart`: its first entry of the set; it runs
/// to the end of its box's run, or kLanes of a cut run: BlockBoxOf). The backend's set is, with reuse,
/// the particles that compute this step, so every lane computes. Masked lanes instead (`idle` set, the
/// set every particle; the layout before the compacted blocks, which sphxr_bench_blocks times and the
/// tests compare with): only the lanes that compute this step (ComputesThisStep) are written, and a
/// block without one costs nothing. The walls' sums (DensityStage::WallSum) are taken the same way, for
/// the lanes whose cell has wall particles around.
struct DensityBlockStage {
  DensityStage stage;
  BlockSet set;                // DensityBlockStart's
  const uint32_t* blockStart;
  const int32_t* idle = nullptr;  // masked lanes: the idle counts; nullptr: every entry computes
  int32_t idleSteps = 0;
  bool pairsOnly = false;  // DensityBlockStart's

  void operator()(int b) const {
    const GridView& g = stage.grid;
    const Vec4* position = stage.fluid.position;
    const uint32_t first = blockStart[b];
    const BlockBox box = BlockBoxOf(g, set, static_cast<int>(first), pairsOnly);
    const int lanes = static_cast<int>(box.end - first < static_cast<uint32_t>(kLanes) ? box.end - first : kLanes);
    uint32_t computing = 0;
    uint32_t particle[kLanes];  // each lane's particle
    const ComputesThisStep computes{idle, idleSteps};
    for (int l = 0; l < lanes; ++l) {
      particle[l] = set.Particle(first + static_cast<uint32_t>(l));
      if (idle == nullptr || computes(static_cast<int>(particle[l]))) computing |= 1u << l;
    }
    if (computing == 0) return;

    Lanes px = Splat(1e30f), py = px, pz = px;
    BlockCells cells(g, box);
    for (int l = 0; l < kLanes; ++l) {
      if (computing & (1u << l)) {
        const Vec4 p = position[particle[l]];
        px[l] = p.x;
        py[l] = p.y;
        pz[l] = p.z;
        cells.Add(p);
      }  // other lanes stay far away, never a hit (their squared distance overflows to +inf)
    }
    const CubicSpline k = stage.ph.kernel;
    uint32_t found[kLanes] = {};
    const Lanes sum = FluidSums(k, cells, computing, particle, px, py, pz, found);
    const Lanes wall = WallSums(k, box, cells, computing, px, py, pz);
    for (int l = 0; l < lanes; ++l) {
      if (computing & (1u << l)) {
        stage.Complete(static_cast<int>(particle[l]), Vec3{px[l], py[l], pz[l]}, sum[l], wall[l], found[l]);
      }
    }
  }

  /// The lanes' fluid kernel sums, and each computing lane's neighbour list (`found`: its neighbour
  /// count, which may pass the list's capacity: the force stage then scans the cells).
  SPHXR_INLINE Lanes FluidSums(const CubicSpline& k, const BlockCells& cells, uint32_t computing,
                               const uint32_t* particle, Lanes px, Lanes py, Lanes pz, uint32_t* found) const {
    const GridView& g = stage.grid;
    const Vec4* position = stage.fluid.position;
    const uint32_t capacity = static_cast<uint32_t>(stage.list.maxNeighbours);
    Lanes sum;
    if constexpr (kVectorAppends) {
      // The neighbour lists without a branch per hit: every candidate that hits some lane is written to
      // every lane's list at that lane's count, and the count moves on where it is a neighbour (a hit
      // that is not the particle itself), so the next candidate overwrites the others. A lane writes
      // into a scratch list with one spare slot (where it writes once its list is full: the count goes
      // on, past the capacity, and the force stage then scans); the lists are copied out at the end.
      const uint32_t stride = capacity + 1;
      thread_local std::vector<uint32_t> scratch;
      if (scratch.size() < static_cast<size_t>(kLanes) * stride) scratch.resize(static_cast<size_t>(kLanes) * stride);
      uint32_t* const lists = scratch.data();
      LaneInts laneList, self, count = LaneInts{};
      for (int l = 0; l < kLanes; ++l) {
        laneList[l] = static_cast<int32_t>(static_cast<uint32_t>(l) * stride);
        self[l] = (computing & (1u << l)) ? static_cast<int32_t>(particle[l]) : -1;
      }
      const LaneInts full = LaneInts{} + static_cast<int32_t>(capacity);
      sum = KernelSumLanes(k, cells, g.fluidStart, g.fluidEnd, position, false, px, py, pz, [&](uint32_t j, LaneInts within) {
        const LaneInts at = laneList + (count < full ? count : full);
        for (int l = 0; l < kLanes; ++l) lists[at[l]] = j;
        count -= within & (self != static_cast<int32_t>(j));  // -1 where a neighbour: the count + 1
      });
      for (int l = 0; l < kLanes; ++l) {
        found[l] = static_cast<uint32_t>(count[l]);
        if (computing & (1u << l)) {
          const uint32_t n = found[l] < capacity ? found[l] : capacity;
          std::memcpy(stage.Slots(static_cast<int>(particle[l])), lists + static_cast<size_t>(l) * stride,
                      n * sizeof(uint32_t));
        }
      }
    } else {
      sum = KernelSumLanes(k, cells, g.fluidStart, g.fluidEnd, position, false, px, py, pz, [&](uint32_t j, LaneInts within) {
        uint32_t hits = Bits(within);
        while (hits != 0) {  // the neighbour lists: every hit but the particle itself
          const int l = __builtin_ctz(hits);
          hits &= hits - 1u;
          const uint32_t i = particle[l];
          if (j == i) continue;
          if (found[l] < capacity) stage.Slots(static_cast<int>(i))[found[l]] = j;
          ++found[l];
        }
      });
    }
    return sum;
  }

  /// The walls' sums of the lanes whose own cell has a wall particle in its 27 cells (WallSum's test);
  /// the others keep 0, as WallSum gives them.
  SPHXR_INLINE Lanes WallSums(const CubicSpline& k, const BlockBox& box, const BlockCells& cells, uint32_t computing,
                              Lanes px, Lanes py, Lanes pz) const {
    const GridView& g = stage.grid;
    Lanes wall = Splat(0.0f);
    bool anyNear = false, allNear = true;
    for (int z = box.z0; z <= box.z1; ++z)
      for (int y = box.y0; y <= box.y1; ++y)
        for (int x = box.x0; x <= box.x1; ++x) {
          const bool near = g.boundaryNear[g.Linear(x, y, z)] != 0;
          anyNear = anyNear || near;
          allNear = allNear && near;
        }
    if (anyNear) {
      Lanes wx = px, wy = py, wz = pz;
      if (!allNear) {
        for (int l = 0; l < kLanes; ++l) {
          if (!(computing & (1u << l))) continue;
          int lx, ly, lz;
          g.CellOf(Vec3{px[l], py[l], pz[l]}, &lx, &ly, &lz);
          if (!g.boundaryNear[g.Linear(lx, ly, lz)]) wx[l] = wy[l] = wz[l] = 1e30f;
        }
      }
      wall = KernelSumLanes(k, cells, g.boundaryStart, g.boundaryEnd, g.boundary, true, wx, wy, wz);
    }
    return wall;
  }
};

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
