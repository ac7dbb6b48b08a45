#pragma once
// The density blocks' layout: which particles share a block (boxes of cells in Morton order, pairs
// of cells cut into runs), the cells around a block, and the kernel sums over them in every lane.
#include <cstdint>
#include <cstring>

#include "cpu/simd.h"
#include "morton.h"
#include "stages/grid.h"
#include "stages/reuse.h"
#include "stages/views.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

/// The pair of cells along x that a density block is drawn from where its particles are many: cells
/// 2m and 2m + 1 of a row, whose Morton codes differ in the lowest bit only, so their particles are one
/// contiguous run (`first`, `end`). With 16 lanes a block from the pair fills the vector better than one
/// cell's ~8, and the pair's 4 x 3 x 3 cells around it are 36 instead of twice 27. A pair of more than
/// kLanes is cut into runs of kLanes, from the pair's first particle or, where that makes fewer
/// candidate loads, from each cell's (CutRunOf): a block's candidates scale with the cells around it,
/// so the cut costs 36 per pair block and 27 per cell block (17 particles, 8 + 9: two pair blocks, 72,
/// or two cell blocks, 54; 40, 20 + 20: three pair blocks, 108, or four cell blocks, 108).
struct CellPair {
  int x0, x1;  // the pair's cells along x (x1 == x0 when the grid ends)
  uint32_t first, end;
};

/// The particles the density blocks are drawn from, as entries in Morton order: every particle (`list`
/// null: entry e is particle e), or with reuse the compacted list of those that compute this step
/// (entry e is particle list[e]), so that a block's lanes are all particles that compute and the
/// particles that reuse take no lane. `rank[i]`: the entries before particle i (n + 1 values, an
/// exclusive scan of the computing flags), so that cell c's entries run from rank[fluidStart[c]] to
/// rank[fluidEnd[c]].
struct BlockSet {
  const uint32_t* keys;            // the entries' sorted Morton keys
  int count;                       // entries
  const uint32_t* list = nullptr;  // entry -> particle; null: the identity
  const uint32_t* rank = nullptr;  // particle -> entries before it; null: the identity
  SPHXR_INLINE uint32_t Particle(uint32_t e) const { return list != nullptr ? list[e] : e; }
  SPHXR_INLINE uint32_t Rank(uint32_t i) const { return rank != nullptr ? rank[i] : i; }
  /// Cell c's entries [*first, *end); false when the cell has no particle at all.
  SPHXR_INLINE bool CellRun(const GridView& g, uint32_t c, uint32_t* first, uint32_t* end) const {
    if (g.fluidStart[c] == kEmptyCell) return false;
    *first = Rank(g.fluidStart[c]);
    *end = Rank(g.fluidEnd[c]);
    return true;
  }
};

/// The run that the blocks of cell (cx, cy, cz)'s particles are cut from when their 2 x 2 x 1 box holds
/// more than kLanes (BlockBoxOf): the pair's, or the cell's own (x0 == x1 == cx) where that is cheaper.
/// `pairsOnly`: always the pair's (the layout before the boxes, which the tests hold the boxes to).
SPHXR_INLINE CellPair CutRunOf(const GridView& g, const BlockSet& set, int cx, int cy, int cz, bool pairsOnly) {
  CellPair pair;
  pair.x0 = cx & ~1;
  pair.x1 = pair.x0 + 1 < g.nx ? pair.x0 + 1 : pair.x0;
  uint32_t f0 = 0, e0 = 0, f1 = 0, e1 = 0;
  const bool has0 = set.CellRun(g, g.Linear(pair.x0, cy, cz), &f0, &e0);
  const bool has1 = set.CellRun(g, g.Linear(pair.x1, cy, cz), &f1, &e1);
  pair.first = has0 ? f0 : f1;
  pair.end = has1 ? e1 : e0;
  const uint32_t n = pair.end - pair.first;
  if (pairsOnly || n <= static_cast<uint32_t>(kLanes) || pair.x1 == pair.x0) return pair;
  const uint32_t n0 = e0 - f0, n1 = e1 - f1;
  if (n0 == 0 || n1 == 0) return pair;  // one cell holds the run already (an empty cell: 0 to 0)
  auto blocks = [](uint32_t m) { return (m + static_cast<uint32_t>(kLanes) - 1) / static_cast<uint32_t>(kLanes); };
  if (27 * (blocks(n0) + blocks(n1)) >= 36 * blocks(n)) return pair;
  return cx == pair.x0 ? CellPair{cx, cx, f0, e0} : CellPair{cx, cx, f1, e1};
}

/// Where particles are few (spray, a thin sheet, the surface), a pair holds two or three and its block
/// leaves most lanes empty. Cells whose Morton codes agree above the lowest m bits form a box
/// (m = 1: 2 x 1 x 1 cells, the pair; 2: 2 x 2 x 1; 3: 2 x 2 x 2; 4: 4 x 2 x 2; 5: 4 x 4 x 2; 6: 4 x 4 x 4)
/// and their particles one contiguous run of the sorted keys. A block is the largest such box, up to
/// level kMaxBlockLevel, whose run fits in kLanes; where not even the 2 x 2 x 1 box fits, the pair's
/// or the cell's run cut into kLanes (CutRunOf). Every particle of a box finds the same box (the boxes
/// of one level tile the grid, and a box that fits holds only boxes that fit), so the blocks tile the
/// particles. The start predicate and the stage each find a block's box (from its first particle);
/// the stage's second look costs a scan of at most 2 kLanes keys per block.
inline constexpr int kMaxBlockLevel = 6;

struct BlockBox {
  int level;             // m: 1 for the cut runs (CutRunOf)
  uint32_t first, end;   // the box's run (level 1: the whole run it is cut from)
  int x0, x1, y0, y1, z0, z1;  // its cells, clamped to the grid
};

/// The block box of entry i of the set (its keys sorted; BlockSet). `pairsOnly`: every
/// block from a pair, cut from the pair's first (the layout before the boxes; the results are the same
/// bit for bit, and tests/sim/cpu_stages_test.cpp checks that they are).
SPHXR_INLINE BlockBox BlockBoxOf(const GridView& g, const BlockSet& set, int i, bool pairsOnly) {
  const uint32_t* keys = set.keys;
  const int n = set.count;
  const uint32_t key = keys[i];
  int lo = i, hi = i + 1, level = 1;
  for (int m = 2; m <= (pairsOnly ? 1 : kMaxBlockLevel); ++m) {  // widen the run level by level while it fits
    const uint32_t top = key >> m;
    int a = lo, b = hi;
    while (a > 0 && (keys[a - 1] >> m) == top && b - a <= kLanes) --a;
    while (b < n && (keys[b] >> m) == top && b - a <= kLanes) ++b;
    if (b - a > kLanes) break;
    lo = a;
    hi = b;
    level = m;
  }
  uint32_t cx, cy, cz;
  MortonDecode(key >> level << level, &cx, &cy, &cz);
  BlockBox box;
  box.level = level;
  box.x0 = static_cast<int>(cx);
  box.y0 = static_cast<int>(cy);
  box.z0 = static_cast<int>(cz);
  const int sx = 1 << ((level + 2) / 3), sy = 1 << ((level + 1) / 3), sz = 1 << (level / 3);
  box.x1 = box.x0 + sx - 1 < g.nx ? box.x0 + sx - 1 : g.nx - 1;
  box.y1 = box.y0 + sy - 1 < g.ny ? box.y0 + sy - 1 : g.ny - 1;
  box.z1 = box.z0 + sz - 1 < g.nz ? box.z0 + sz - 1 : g.nz - 1;
  if (level == 1) {
    const CellPair run = CutRunOf(g, set, static_cast<int>(MortonCompact(key)), box.y0, box.z0, pairsOnly);
    box.x0 = run.x0;
    box.x1 = run.x1;
    box.first = run.first;
    box.end = run.end;
  } else {
    box.first = static_cast<uint32_t>(lo);
    box.end = static_cast<uint32_t>(hi);
  }
  return box;
}

/// Whether entry i of the set starts a density block: the first of its box, or (a pair's cut runs)
/// kLanes, 2 kLanes, ... after the run's first. Its cell comes from the step's sorted Morton keys
/// (CellCodeStage), not from its position again. An entry that is not its cell's first can start a
/// block only as a cut (its box's first is some cell's first), so only cells' firsts look for a box.
struct DensityBlockStart {
  GridView grid;
  BlockSet set;
  bool pairsOnly = false;  // BlockBoxOf's
  bool operator()(int i) const {
    const uint32_t key = set.keys[i];
    if (i > 0 && set.keys[i - 1] == key) {
      uint32_t cx, cy, cz;
      MortonDecode(key, &cx, &cy, &cz);
      const CellPair run =
          CutRunOf(grid, set, static_cast<int>(cx), static_cast<int>(cy), static_cast<int>(cz), pairsOnly);
      return (static_cast<uint32_t>(i) - run.first) % kLanes == 0;
    }
    const BlockBox box = BlockBoxOf(grid, set, i, pairsOnly);
    return (static_cast<uint32_t>(i) - box.first) % kLanes == 0;
  }
};

/// The cells around a block of lanes whose particles lie in one box of cells (x0..x1, y0..y1, z0..z1)
/// of the grid: the box's neighbour cells (27 around one cell, 36 around a pair, up to 216 around a
/// 4 x 4 x 4 box), less those no lane can reach. Each lane's position, clamped to the box (as
/// ForEachInCells clamps to a particle's cell), widens the block's extent per axis; a cell a cell size
/// (>= the support) or more from that extent holds no particle within any lane's support. The cells
/// are visited in ForEachInCells' order (z, y, x), so each lane meets its candidates in the order its
/// own scan would: its own 27 cells come in that order among the box's, and the other cells hold no
/// particle within its support.
struct BlockCells {
  const GridView* g;
  int x0, x1, y0, y1, z0, z1;
  float origin[3], extent[3], lo[3], hi[3];

  BlockCells(const GridView& grid, int boxX0, int boxX1, int boxY0, int boxY1, int boxZ0, int boxZ1)
      : g(&grid), x0(boxX0), x1(boxX1), y0(boxY0), y1(boxY1), z0(boxZ0), z1(boxZ1) {
    const float cs = grid.cellSize;
    origin[0] = grid.origin.x + static_cast<float>(x0) * cs;
    origin[1] = grid.origin.y + static_cast<float>(y0) * cs;
    origin[2] = grid.origin.z + static_cast<float>(z0) * cs;
    extent[0] = static_cast<float>(x1 - x0 + 1) * cs;
    extent[1] = static_cast<float>(y1 - y0 + 1) * cs;
    extent[2] = static_cast<float>(z1 - z0 + 1) * cs;
    for (int a = 0; a < 3; ++a) {
      lo[a] = extent[a];
      hi[a] = 0.0f;
    }
  }
  BlockCells(const GridView& grid, const BlockBox& box)
      : BlockCells(grid, box.x0, box.x1, box.y0, box.y1, box.z0, box.z1) {}
  /// Widens the extent by one lane's position.
  void Add(const Vec4& p) {
    const float local[3] = {p.x - origin[0], p.y - origin[1], p.z - origin[2]};
    for (int a = 0; a < 3; ++a) {
      const float t = AtMost(AtLeast(local[a], 0.0f), extent[a]);
      lo[a] = AtMost(lo[a], t);
      hi[a] = AtLeast(hi[a], t);
    }
  }
  /// f(j) for every particle j (ranges start/end) of the cells around the box that the extent reaches.
  template <class F>
  void ForEach(const uint32_t* start, const uint32_t* end, F&& f) const {
    const GridView& grid = *g;
    const float cs = grid.cellSize;
    const int base[3] = {x0, y0, z0};
    // Squared distance along `axis` from the block's extent to cell c.
    auto gap = [&](int axis, int c) {
      const float cellLo = static_cast<float>(c - base[axis]) * cs, cellHi = cellLo + cs;
      const float d = AtLeast(AtLeast(cellLo - hi[axis], lo[axis] - cellHi), 0.0f);
      return d * d;
    };
    const float reach2 = cs * cs;
    const int za = z0 > 0 ? z0 - 1 : 0, zb = z1 < grid.nz - 1 ? z1 + 1 : z1;
    const int ya = y0 > 0 ? y0 - 1 : 0, yb = y1 < grid.ny - 1 ? y1 + 1 : y1;
    const int xa = x0 > 0 ? x0 - 1 : 0, xb = x1 < grid.nx - 1 ? x1 + 1 : x1;
    for (int z = za; z <= zb; ++z) {
      const float dz2 = gap(2, z);
      for (int y = ya; y <= yb; ++y) {
        const float dyz2 = dz2 + gap(1, y);
        if (dyz2 >= reach2) continue;
        const uint32_t row = grid.Linear(0, y, z);
        for (int x = xa; x <= xb; ++x) {
          if (dyz2 + gap(0, x) >= reach2) continue;
          const uint32_t s = start[row + x];
          if (s == kEmptyCell) continue;
          const uint32_t e = end[row + x];
          for (uint32_t j = s; j < e; ++j) f(j);
        }
      }
    }
  }
};

/// sum_j w_j W(|x_l - x_j|) in every lane l over the particles j of `points` that `cells` reaches, in
/// its order (w_j = `points[j].w`, or 1 when `weighted` is false). Lanes far away (1e30) never hit.
/// onHits(j, within) sees each candidate within some lane's support (within: all ones in those lanes).
template <class OnHits>
inline Lanes KernelSumLanes(const CubicSpline& k, const BlockCells& cells, const uint32_t* start, const uint32_t* end,
                            const Vec4* points, bool weighted, Lanes px, Lanes py, Lanes pz, OnHits&& onHits) {
  Lanes sum = Splat(0.0f);
  cells.ForEach(start, end, [&](uint32_t j) {
    const Vec4 pj = points[j];
    const Lanes dx = px - pj.x, dy = py - pj.y, dz = pz - pj.z;
    const Lanes r2 = dx * dx + dy * dy + dz * dz;
    const LaneInts within = Less(r2, Splat(k.H2));
    if (Bits(within) == 0) return;
    const Lanes w = KernelWLanes(k, Sqrt(r2) * k.invH, within);
    sum += weighted ? pj.w * w : w;
    onHits(j, within);
  });
  return sum;
}
inline Lanes KernelSumLanes(const CubicSpline& k, const BlockCells& cells, const uint32_t* start, const uint32_t* end,
                            const Vec4* points, bool weighted, Lanes px, Lanes py, Lanes pz) {
  return KernelSumLanes(k, cells, start, end, points, weighted, px, py, pz, [](uint32_t, LaneInts) {});
}

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
