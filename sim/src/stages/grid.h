#pragma once
// Stages 1 and 3 of a step: each particle's cell code (Morton order, Huang et al. 2013, sec. 3.1) and
// the cell ranges of the sorted particles; and, once at set-up, the cells with walls near them.
#include <cstdint>

#include "morton.h"
#include "stages/views.h"

namespace sphxr::sim {

// ---- stage 1: cell codes -------------------------------------------------------------------------
struct CellCodeStage {
  GridView grid;
  const Vec4* position;
  uint32_t* keys;
  uint32_t* order;
  /// A device flag that gates the grid (PressureSolver::GridGate), or nullptr. Where it is 0 the keys
  /// keep their sorted values: the stable sort then leaves every particle where it is and the ranges
  /// come out as they were.
  const int* gate = nullptr;
  SPHXR_HD void operator()(int i) const {
    order[i] = static_cast<uint32_t>(i);
    if (gate && *gate == 0) return;
    int cx, cy, cz;
    grid.CellOf(Xyz(position[i]), &cx, &cy, &cz);
    keys[i] = MortonEncode(static_cast<uint32_t>(cx), static_cast<uint32_t>(cy), static_cast<uint32_t>(cz));
  }
};

// ---- stage 3: cell ranges from sorted particles --------------------------------------------------
// ---- stage 2: the sort's reorder ------------------------------------------------------------------
/// Every field of the list gathered into the sorted order at once: to.name[i] = from.name[order[i]], one
/// work item per particle (one kernel for all fields, not one gather per field).
struct ReorderFieldsStage {
  FluidView from, to;
  const uint32_t* order;
  SPHXR_HD void operator()(int i) const {
    const uint32_t j = order[i];
#define SPHXR_GATHER_FIELD(type, name) to.name[i] = from.name[j];
    SPHXR_FLUID_FIELDS(SPHXR_GATHER_FIELD)
#undef SPHXR_GATHER_FIELD
  }
};

struct CellRangeStage {
  GridView grid;
  const Vec4* position;  // sorted
  const uint32_t* keys;  // sorted
  uint32_t* start;
  uint32_t* end;
  int count;
  SPHXR_HD void operator()(int i) const {
    const uint32_t key = keys[i];
    if (i > 0 && keys[i - 1] == key && i < count - 1 && keys[i + 1] == key) return;
    int cx, cy, cz;
    grid.CellOf(Xyz(position[i]), &cx, &cy, &cz);
    const uint32_t cell = grid.Linear(cx, cy, cz);
    if (i == 0 || keys[i - 1] != key) start[cell] = static_cast<uint32_t>(i);
    if (i == count - 1 || keys[i + 1] != key) end[cell] = static_cast<uint32_t>(i + 1);
  }
};

/// f(n) for the linear index n of each of the 27 cells around cell (cx, cy, cz) that lie in the grid,
/// in z, y, x order.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachCellAround(const GridView& grid, int cx, int cy, int cz, F&& f) {
  for (int z = cz - 1; z <= cz + 1; ++z)
    for (int y = cy - 1; y <= cy + 1; ++y)
      for (int x = cx - 1; x <= cx + 1; ++x) {
        if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz) continue;
        f(grid.Linear(x, y, z));
      }
}

// ---- cells near the boundary (once): any boundary particle in the 27 cells around cell c ------------
/// Whether any of the 27 cells around linear cell c (within the grid) is non-empty in `start`.
SPHXR_HD SPHXR_INLINE bool AnyInNeighbourCells(const GridView& grid, const uint32_t* start, int c) {
  int cx, cy, cz;
  grid.CellCoords(c, &cx, &cy, &cz);
  bool any = false;
  ForEachCellAround(grid, cx, cy, cz, [&](uint32_t n) {
    if (start[n] != kEmptyCell) any = true;
  });
  return any;
}

/// Predicate for compacting cell indices: the cell's start is not kEmptyCell.
struct NonEmptyCell {
  SPHXR_HD bool operator()(uint32_t start) const { return start != kEmptyCell; }
};

struct BoundaryNearStage {
  GridView grid;
  uint8_t* out;
  SPHXR_HD void operator()(int c) const { out[c] = AnyInNeighbourCells(grid, grid.boundaryStart, c) ? 1 : 0; }
};

}  // namespace sphxr::sim
