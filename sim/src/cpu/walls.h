#pragma once
// WallPressureStage (stages/walls.h) for the wall particles of one cell, kLanes at a time.
#include <cstdint>

#include "cpu/blocks.h"
#include "cpu/simd.h"
#include "stages/walls.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

/// WallPressureStage for the wall particles of cell `cells[k]`, kLanes at a time: each lane's kernel sum
/// over the fluid around the cell, in the order of its own scan.
struct WallPressureBlockStage {
  WallPressureStage stage;

  void operator()(int item) const {
    const GridView& g = stage.grid;
    const uint32_t c = stage.cells[item];
    const uint32_t s = g.boundaryStart[c], e = g.boundaryEnd[c];
    if (!AnyInNeighbourCells(g, g.fluidStart, static_cast<int>(c))) {
      for (uint32_t b = s; b < e; ++b) stage.out[b] = 0.0f;
      return;
    }
    int cx, cy, cz;
    g.CellCoords(static_cast<int>(c), &cx, &cy, &cz);
    for (uint32_t first = s; first < e; first += kLanes) {
      const int lanes = static_cast<int>(e - first < static_cast<uint32_t>(kLanes) ? e - first : kLanes);
      Lanes px = Splat(1e30f), py = px, pz = px;
      BlockCells cells(g, cx, cx, cy, cy, cz, cz);
      for (int l = 0; l < lanes; ++l) {
        const Vec4 p = g.boundary[first + l];
        px[l] = p.x;
        py[l] = p.y;
        pz[l] = p.z;
        cells.Add(p);
      }
      const Lanes sum = KernelSumLanes(stage.ph.kernel, cells, g.fluidStart, g.fluidEnd, stage.fluid.position, false, px, py, pz);
      for (int l = 0; l < lanes; ++l) stage.out[first + l] = stage.FromSum(static_cast<int>(first) + l, sum[l]);
    }
  }
};

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
