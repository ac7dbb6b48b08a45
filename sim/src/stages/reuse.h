#pragma once
// Stage 3b of a step with activity-based reuse (Huang et al. 2013, sec. 3.3; the impulse hold,
// docs/design/impulse_hold.md): the cells' crowding, each particle's classification, and the
// predicates and wrapper that run a stage over the compacted list of particles that compute. The
// hold's kick is IntegrateStage's (stages/integrate.h).
#include <cstddef>
#include <cstdint>

#include "stages/views.h"

namespace sphxr::sim {

// ---- stage 3b: activity (reuse on) ---------------------------------------------------------------
/// Each cell's particles, fluid and wall (reuse only; every cell, empty ones 0): what CellBoxSumStage sums.
/// Wall particles count too: water along a wall is crowded, not sparse, although the cells beyond the
/// wall hold no fluid.
struct CellCountStage {
  GridView grid;
  uint32_t* count;
  SPHXR_HD void operator()(int c) const {
    uint32_t particles = 0;
    if (grid.fluidStart[c] != kEmptyCell) particles += grid.fluidEnd[c] - grid.fluidStart[c];
    if (grid.boundaryStart[c] != kEmptyCell) particles += grid.boundaryEnd[c] - grid.boundaryStart[c];
    count[c] = particles;
  }
};

/// One of the three passes of the sum of CellCountStage's counts over the 27 cells around every cell
/// (reuse only): the activity stage's crowding N_i. Along `axis` (0 x, 1 y, 2 z), out[c] = in[c - s] +
/// in[c] + in[c + s], s the axis' stride, a neighbour outside the grid counting 0; the x, y and z passes
/// in turn give each cell the particles of its 27 cells exactly (integers), with 9 loads per cell and no
/// division. One work item per row of cells along x (row = cy + ny cz): summing 27 cells per fluid cell,
/// or per particle, costs a few percent of a step.
struct CellBoxSumStage {
  GridView grid;
  const uint32_t* in;
  uint32_t* out;
  int axis;
  SPHXR_HD void operator()(int row) const {
    const int nx = grid.nx;
    const size_t first = static_cast<size_t>(row) * static_cast<size_t>(nx);
    const uint32_t* mid = in + first;
    uint32_t* o = out + first;
    if (axis == 0) {
      if (nx == 1) {
        o[0] = mid[0];
        return;
      }
      o[0] = mid[0] + mid[1];
      for (int x = 1; x < nx - 1; ++x) o[x] = mid[x - 1] + mid[x] + mid[x + 1];
      o[nx - 1] = mid[nx - 2] + mid[nx - 1];
      return;
    }
    const int cy = row % grid.ny, cz = row / grid.ny;
    const size_t stride = axis == 1 ? static_cast<size_t>(nx) : static_cast<size_t>(nx) * static_cast<size_t>(grid.ny);
    const bool below = axis == 1 ? cy > 0 : cz > 0;
    const bool above = axis == 1 ? cy + 1 < grid.ny : cz + 1 < grid.nz;
    if (below && above) {
      const uint32_t* lo = mid - stride;
      const uint32_t* hi = mid + stride;
      for (int x = 0; x < nx; ++x) o[x] = lo[x] + mid[x] + hi[x];
    } else if (below || above) {
      const uint32_t* other = below ? mid - stride : mid + stride;
      for (int x = 0; x < nx; ++x) o[x] = other[x] + mid[x];
    } else {
      for (int x = 0; x < nx; ++x) o[x] = mid[x];
    }
  }
};

// Idle count IC: -1 active. A particle with IC > 0 reuses this step (density, pressure, acceleration
// stay as they are) and counts down; at IC = 0, or when active, it computes this step and is classified
// with its previous pressure and the crowding of its cells: ACT_i < T gives IC = IDLE, else -1. So a
// particle never reuses more than IDLE consecutive steps. After this stage, "computes this step" is
// exactly IC < 0 or IC == IDLE (ComputesThisStep).
struct ActivityStage {
  GridView grid;
  FluidView fluid;
  Physics ph;
  const uint32_t* crowd;  // CellBoxSumStage's three passes: the particles of the 27 cells around each cell
  SPHXR_HD void operator()(int i) const {
    // Paddles: a particle near a moving boundary always computes (its neighbourhood changes every step).
    if (grid.MovingNear(Xyz(fluid.position[i]))) {
      fluid.idle[i] = -1;
      return;
    }
    const int32_t ic = fluid.idle[i];
    if (ic > 0) {  // reuses this step
      fluid.idle[i] = ic - 1;
      return;
    }
    // The impulse hold's synchronised schedule: particles go inactive together, on every (IDLE + 1)-th
    // step, so a calm region reuses over the same steps and computes on the same step (docs/design/impulse_hold.md).
    // On the other steps the crowding is not computed (BackendImpl::Step) and not read.
    if (!ph.reuseSyncStep) {
      fluid.idle[i] = -1;
      return;
    }
    int cx, cy, cz;
    grid.CellOf(Xyz(fluid.position[i]), &cx, &cy, &cz);
    // The mean over all 27 cells, those outside the grid as empty: a particle there is at an edge.
    const float meanCount = static_cast<float>(crowd[grid.Linear(cx, cy, cz)]) / 27.0f;
    const float act = ph.reuseDelta1 * fluid.pressure[i] * ph.reuseInvPressureScale +
                      ph.reuseDelta2 * ph.reuseCellCount / AtLeast(meanCount, 1e-6f);
    fluid.idle[i] = (act < ph.reuseThreshold && ph.reuseIdle > 0) ? ph.reuseIdle : -1;
  }
};

struct ComputesThisStep {
  const int32_t* idle;
  int32_t idleSteps;
  SPHXR_HD bool operator()(int i) const { return idle[i] < 0 || idle[i] == idleSteps; }
};

/// 1 for a particle i < n whose density is computed this step, else 0 (also for i = n: the CPU density
/// blocks' rank scan runs over n + 1 items, cpu/blocks.h BlockSet).
struct ComputeFlag {
  ComputesThisStep density;
  int n;
  SPHXR_HD uint32_t operator()(int i) const { return i < n && density(i) ? 1u : 0u; }
};

/// Runs a per-particle stage over a compacted list of particle indices.
template <class Stage>
struct OverList {
  const uint32_t* list;
  Stage stage;
  SPHXR_HD void operator()(int k) const { stage(static_cast<int>(list[k])); }
};

}  // namespace sphxr::sim
