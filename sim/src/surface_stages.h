#pragma once
// The stages of histogram-pyramid marching cubes (Dyken, Ziegler, Theobalt, Seidel 2008, "High-speed
// marching cubes using histogram pyramids"), written once as host+device functors over raw pointers.
// surface_impl.h launches them with thrust on the OpenMP system (CPU backend) or the CUDA system.
//
//   1. lattice    the box the domain clamp keeps the particles in, plus a margin (host arithmetic from
//                 the scene: nothing is read back, and the lattice keeps its size from frame to frame)
//   2. field      phi at every sample, through the neighbour grid's cellStart/cellEnd: one work item
//                 per block of neighbour cells adds each candidate particle's kernel to the block's
//                 samples within its reach (a clipped box); a block with no particle in reach writes zeros
//   3. base       level 0 of the pyramid: the vertex count of each cell's marching-cubes case (and the
//                 case), fused with level 1 (the 2x2x2 sums of the base) in one pass over the field
//   4. reduce     level l node = sum of its 2x2x2 children in level l-1, up to the apex (the total)
//   5. traverse   launched over the target's capacity, not the apex (which stays on the device): items
//                 past the apex return at once, item 0 reports the count (and fills an indirect draw);
//                 one work item per run of consecutive output vertices (one vertex on the GPU): the
//                 first walks down from the apex, at each level skipping the children whose counts
//                 lie before the vertex's index, to its cell and the vertex's slot there; the others
//                 step to the next slot or the next cell with vertices (the in-order successor); the
//                 case table names the edge; the position is interpolated on it and the normal is
//                 -grad phi (central differences), interpolated the same way.
// No per-cell output buffer of the worst-case size exists: the mesh has exactly apex vertices.
#include <cstdint>

#include "kernel.h"
#include "mc_tables.h"
#include "sphxr/common/hd.h"
#include "sphxr/sim/surface.h"
#include "sphxr/sim/vec.h"
#include "stages.h"

namespace sphxr::sim {

inline constexpr int kMaxPyramidLevels = 32;

/// The particles' bounding box (the CPU backend's surface lattice: kSurfaceOverParticles).
struct Bounds {
  Vec3 min{1e30f, 1e30f, 1e30f};
  Vec3 max{-1e30f, -1e30f, -1e30f};
};

struct BoundsOfPoint {
  const Vec4* position;
  SPHXR_HD Bounds operator()(int i) const {
    const Vec3 p = Xyz(position[i]);
    return Bounds{p, p};
  }
};

struct BoundsCombine {
  SPHXR_HD Bounds operator()(const Bounds& a, const Bounds& b) const {
    return Bounds{{fminf(a.min.x, b.min.x), fminf(a.min.y, b.min.y), fminf(a.min.z, b.min.z)},
                  {fmaxf(a.max.x, b.max.x), fmaxf(a.max.y, b.max.y), fmaxf(a.max.z, b.max.z)}};
  }
};

/// The sample lattice and its field on the device.
struct FieldView {
  Vec3 origin;
  float cellSize;
  float halfInvCellSize;  // 1 / (2 cellSize), for central differences
  int nx, ny, nz;
  float iso;
  const float* value;  // nx * ny * nz samples, x fastest (fewer than 2^31: Solver limits the lattice)

  SPHXR_HD SPHXR_INLINE int Index(int i, int j, int k) const { return i + nx * (j + ny * k); }
  SPHXR_HD SPHXR_INLINE Vec3 Point(int i, int j, int k) const {
    return Vec3{origin.x + static_cast<float>(i) * cellSize, origin.y + static_cast<float>(j) * cellSize,
                origin.z + static_cast<float>(k) * cellSize};
  }
  /// grad phi at a sample: central differences inside, one-sided at the lattice's border.
  SPHXR_HD SPHXR_INLINE Vec3 Gradient(int i, int j, int k) const {
    const int s = Index(i, j, k);
    auto diff = [&](int at, int n, int stride) {
      const int lo = at > 0 ? s - stride : s, hi = at < n - 1 ? s + stride : s;
      const float scale = (at > 0 && at < n - 1) ? halfInvCellSize : 2.0f * halfInvCellSize;
      return (value[hi] - value[lo]) * scale;  // 0 when the lattice is one sample thick on this axis
    };
    return Vec3{diff(i, nx, 1), diff(j, ny, nx), diff(k, nz, nx * ny)};
  }
};

// ---- 2. the field: phi(x) = sum_j V W(|x - x_j|), V = m / rho0 --------------------------------------
/// One work item per block of B x B x B neighbour-grid cells under the lattice, for all the samples
/// whose cell (GridView::CellOf) lies in the block (at most kMaxBlock per axis). The candidates are the
/// particles of the block's cells and of the ring of cells around it, read once; each one adds its
/// kernel to the samples inside its reach box [q - H, q + H], clipped to the block's samples
/// arithmetically, so a sample is tested only against particles whose box holds it. Per sample the
/// particles are added in the order of ForEachInCells (z, y, x, then the cell's range) restricted to
/// the particles within the support: the value is that of a per-sample gather up to the rounding of
/// r^2. A block with no particle in reach writes zeros. Lattices much finer than the support (more than
/// kMaxBlock samples per neighbour cell) gather sample by sample.
struct FieldStage {
  static constexpr int kMaxBlock = 8;
  GridView grid;
  const Vec4* position;  // sorted fluid positions (the grid's cell ranges index them)
  CubicSpline kernel;
  float volume;          // m / rho0 = dx^3
  FieldView field;
  int c0x, c0y, c0z;     // the first neighbour cell under the lattice
  int c1x, c1y, c1z;     // the last one
  int block;             // B, neighbour cells per block and axis
  int blocksX, blocksY;  // blocks per axis (blocksZ implied by the launch size)
  float* out;

  /// Samples [first, first + count) along one axis whose neighbour cell is c (CellOf's arithmetic).
  SPHXR_HD SPHXR_INLINE static void AxisRange(int c, int cells, float gridOrigin, float invCell, float cellSize,
                                              float latticeOrigin, float spacing, int samples, int* first, int* count) {
    const float lo = gridOrigin + static_cast<float>(c) * cellSize, hi = lo + cellSize;
    int a = c == 0 ? 0 : static_cast<int>(floorf((lo - latticeOrigin) / spacing)) - 1;
    int b = c == cells - 1 ? samples - 1 : static_cast<int>(ceilf((hi - latticeOrigin) / spacing)) + 1;
    a = a < 0 ? 0 : a;
    b = b > samples - 1 ? samples - 1 : b;
    auto cellOf = [&](int i) {
      const float p = latticeOrigin + static_cast<float>(i) * spacing;
      const int k = static_cast<int>(fmaxf(0.0f, fminf((p - gridOrigin) * invCell, 1e9f)));
      return k > cells - 1 ? cells - 1 : k;
    };
    while (a <= b && cellOf(a) < c) ++a;
    while (b >= a && cellOf(b) > c) --b;
    *first = a;
    *count = b - a + 1;
  }

  /// Samples of neighbour cells [c, c + n) along one axis, clipped to the last cell under the lattice.
  SPHXR_HD SPHXR_INLINE void BlockRange(int c, int last, int cells, float gridOrigin, float latticeOrigin,
                                        int samples, int* first, int* count) const {
    const int e = c + block - 1 < last ? c + block - 1 : last;
    int a, na, b, nb;
    AxisRange(c, cells, gridOrigin, grid.invCellSize, grid.cellSize, latticeOrigin, field.cellSize, samples, &a, &na);
    AxisRange(e, cells, gridOrigin, grid.invCellSize, grid.cellSize, latticeOrigin, field.cellSize, samples, &b, &nb);
    *first = a;
    *count = b + nb - a;
  }

  /// Indices [lo, hi] of the samples first + i (i in [0, n)) at spacing h with |s_i - q| < reach.
  SPHXR_HD SPHXR_INLINE static void Clip(float q, float first, float invH, float reachCells, int n, int* lo, int* hi) {
    const float t = (q - first) * invH;
    if (!(fabsf(t) < 1e9f)) {  // a non-finite particle (or one 1e9 samples away) reaches no sample
      *lo = 0;
      *hi = -1;
      return;
    }
    const int a = static_cast<int>(ceilf(t - reachCells)), b = static_cast<int>(floorf(t + reachCells));
    *lo = a < 0 ? 0 : a;
    *hi = b > n - 1 ? n - 1 : b;
  }

  SPHXR_HD void operator()(int b) const {
    const int bx = b % blocksX, by = (b / blocksX) % blocksY, bz = b / (blocksX * blocksY);
    const int cx = c0x + bx * block, cy = c0y + by * block, cz = c0z + bz * block;
    int i0, ni, j0, nj, k0, nk;
    BlockRange(cx, c1x, grid.nx, grid.origin.x, field.origin.x, field.nx, &i0, &ni);
    BlockRange(cy, c1y, grid.ny, grid.origin.y, field.origin.y, field.ny, &j0, &nj);
    BlockRange(cz, c1z, grid.nz, grid.origin.z, field.origin.z, field.nz, &k0, &nk);
    if (ni <= 0 || nj <= 0 || nk <= 0) return;
    const CubicSpline w = kernel;
    // The block's cells and their ring.
    const int ex = cx + block - 1 < c1x ? cx + block - 1 : c1x;
    const int ey = cy + block - 1 < c1y ? cy + block - 1 : c1y;
    const int ez = cz + block - 1 < c1z ? cz + block - 1 : c1z;
    const int x0 = cx > 0 ? cx - 1 : 0, x1 = ex < grid.nx - 1 ? ex + 1 : ex;
    const int y0 = cy > 0 ? cy - 1 : 0, y1 = ey < grid.ny - 1 ? ey + 1 : ey;
    const int z0 = cz > 0 ? cz - 1 : 0, z1 = ez < grid.nz - 1 ? ez + 1 : ez;
    if (ni > kMaxBlock || nj > kMaxBlock || nk > kMaxBlock) {
      for (int k = 0; k < nk; ++k)
        for (int j = 0; j < nj; ++j)
          for (int i = 0; i < ni; ++i) {
            float sum = 0.0f;
            ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, position, field.Point(i0 + i, j0 + j, k0 + k),
                           [&](uint32_t, Vec3 d) {
                             const float r2 = Dot(d, d);
                             if (r2 < w.H2) sum += w.W(sqrtf(r2));
                           });
            out[field.Index(i0 + i, j0 + j, k0 + k)] = volume * sum;
          }
      return;
    }
    float sum[kMaxBlock * kMaxBlock * kMaxBlock];
    for (int s = 0; s < ni * nj * nk; ++s) sum[s] = 0.0f;
    const Vec3 first = field.Point(i0, j0, k0);
    const float h = field.cellSize, invH = 1.0f / h, reach = w.H * invH;
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y) {
        const uint32_t row = grid.Linear(0, y, z);
        for (int x = x0; x <= x1; ++x) {
          const uint32_t s0 = grid.fluidStart[row + x];
          if (s0 == kEmptyCell) continue;
          const uint32_t s1 = grid.fluidEnd[row + x];
          for (uint32_t p = s0; p < s1; ++p) {
            const Vec4 q = position[p];
            int ia, ib, ja, jb, ka, kb;
            Clip(q.x, first.x, invH, reach, ni, &ia, &ib);
            Clip(q.y, first.y, invH, reach, nj, &ja, &jb);
            Clip(q.z, first.z, invH, reach, nk, &ka, &kb);
            for (int k = ka; k <= kb; ++k) {
              const float dz = first.z + static_cast<float>(k) * h - q.z, dz2 = dz * dz;
              for (int j = ja; j <= jb; ++j) {
                const float dy = first.y + static_cast<float>(j) * h - q.y, dyz2 = dz2 + dy * dy;
                if (dyz2 >= w.H2) continue;
                float* line = sum + (k * nj + j) * ni;
                for (int i = ia; i <= ib; ++i) {
                  const float dx = first.x + static_cast<float>(i) * h - q.x, r2 = dyz2 + dx * dx;
                  if (r2 < w.H2) line[i] += w.W(sqrtf(r2));
                }
              }
            }
          }
        }
      }
    for (int k = 0; k < nk; ++k)
      for (int j = 0; j < nj; ++j)
        for (int i = 0; i < ni; ++i) out[field.Index(i0 + i, j0 + j, k0 + k)] = volume * sum[(k * nj + j) * ni + i];
  }
};

/// The pyramid's levels in one array: level 0 is one node per cell, each level above halves every
/// dimension (rounding up) until the apex, a single node.
/// - Level 0 (the base) is linear, x fastest: one word per cell, its vertex count in the low byte and
///   its marching-cubes case above it (kCaseShift), so that the traversal does not read the cell's 8
///   samples again; then one zero, the sentinel that children beyond the base's edge read.
/// - Levels >= 1 are stored in 2x2x2 bricks (node (x, y, z) in brick (x/2, y/2, z/2), slot x&1 +
///   2 (y&1) + 4 (z&1); slots beyond a level's edge count 0), and a slot holds the running sum of the
///   brick's counts up to and including its own. So the 8 children of a node of level >= 2 are 32
///   contiguous bytes whose last word is the node's count, and the traversal picks a child with 8
///   independent compares. Padding only the levels above the base keeps the pyramid within ~1.16x its
///   base.
struct PyramidView {
  static constexpr int kCaseShift = 8;
  static constexpr uint32_t kCountMask = 0xffu;
  int levels;
  int dims[kMaxPyramidLevels][3];    // nodes per axis
  int bricks[kMaxPyramidLevels][3];  // ceil(dims / 2), levels >= 1
  int offset[kMaxPyramidLevels];
  int sentinel;                      // index of a 0 (after the base level)
  uint32_t* count;

  /// Level >= 1: the 8 running sums of brick (x, y, z); the last is the count of its parent node.
  SPHXR_HD SPHXR_INLINE const uint32_t* Brick(int level, int x, int y, int z) const {
    return count + offset[level] + 8 * (x + bricks[level][0] * (y + bricks[level][1] * z));
  }
  /// The vertex count of a level >= 1 node.
  SPHXR_HD SPHXR_INLINE uint32_t Total(int level, int x, int y, int z) const {
    if (level == 0) return count[x + dims[0][0] * (y + dims[0][1] * z)] & kCountMask;
    return Brick(level - 1, x, y, z)[7];
  }
};

// ---- 3. base level and level 1, fused: vertices of each cell's case, and their 2x2x2 sums ---------
/// One work item per row segment of level-1 bricks: kSegment bricks along x at brick row (by, bz),
/// i.e. cells [4 kSegment seg, + 4 kSegment) x [4 by, 4 by + 4) x [4 bz, 4 bz + 4). Each of the 16 cell
/// rows is one plain loop along x over its 4 sample rows (8 compares and a table look-up per cell,
/// written so that the compiler vectorises it); then the rows' words are summed 2x2x2 into the
/// segment's level-1 nodes (the counts are the words' low bytes and 8 of them stay below 256, so the
/// sum of 8 words masked once is the sum of their counts), written as their bricks' running sums.
/// Every level-1 slot, padding included, is written.
struct BaseLevelStage {
  static constexpr int kSegment = 8;  // level-1 bricks per work item along x
  FieldView field;
  PyramidView pyramid;
  const uint32_t* baseWord;  // per case: its vertex count | case << kCaseShift, on this system
  int segments;              // per brick row: ceil(bricks[1][0] / kSegment)

  SPHXR_HD void operator()(int item) const {
    const int seg = item % segments, by = (item / segments) % pyramid.bricks[1][1];
    const int bz = item / (segments * pyramid.bricks[1][1]);
    const int cnx = field.nx - 1, cny = field.ny - 1, cnz = field.nz - 1;
    const int i0 = 4 * kSegment * seg, j0 = 4 * by, k0 = 4 * bz;
    const int n = cnx - i0 < 4 * kSegment ? cnx - i0 : 4 * kSegment;  // cells along x
    const int rj = cny - j0 < 4 ? cny - j0 : 4, rk = cnz - k0 < 4 ? cnz - k0 : 4;
    const float iso = field.iso;
    uint32_t* base = pyramid.count;
    for (int ck = 0; ck < rk; ++ck)
      for (int cj = 0; cj < rj; ++cj) {
        const float* __restrict__ a0 = field.value + field.Index(i0, j0 + cj, k0 + ck);
        const float* __restrict__ a1 = a0 + field.nx;
        const float* __restrict__ a2 = a0 + field.nx * field.ny;
        const float* __restrict__ a3 = a2 + field.nx;
        uint32_t mcCase[4 * kSegment];  // first the cases (a loop the compiler vectorises), then the look-ups
        for (int i = 0; i < n; ++i) {
          mcCase[i] = (a0[i] > iso ? 1u : 0u) | (a0[i + 1] > iso ? 2u : 0u) | (a1[i] > iso ? 4u : 0u) |
                      (a1[i + 1] > iso ? 8u : 0u) | (a2[i] > iso ? 16u : 0u) | (a2[i + 1] > iso ? 32u : 0u) |
                      (a3[i] > iso ? 64u : 0u) | (a3[i + 1] > iso ? 128u : 0u);
        }
        uint32_t* out = base + i0 + cnx * (j0 + cj + cny * (k0 + ck));
        for (int i = 0; i < n; ++i) out[i] = baseWord[mcCase[i]];
      }
    // Level-1 nodes (x, J, K) of the segment, J, K in {0, 1}: the sum of their existing cells.
    uint32_t node[2 * kSegment][4];
    for (int x = 0; x < 2 * kSegment; ++x)
      for (int r = 0; r < 4; ++r) node[x][r] = 0;
    for (int ck = 0; ck < rk; ++ck)
      for (int cj = 0; cj < rj; ++cj) {
        const uint32_t* row = base + i0 + cnx * (j0 + cj + cny * (k0 + ck));
        uint32_t* to = &node[0][(cj >> 1) + 2 * (ck >> 1)];
        for (int i = 0; i + 1 < n; i += 2) to[4 * (i >> 1)] += row[i] + row[i + 1];
        if (n & 1) to[4 * (n >> 1)] += row[n - 1];
      }
    const int bricks = pyramid.bricks[1][0] - kSegment * seg < kSegment ? pyramid.bricks[1][0] - kSegment * seg : kSegment;
    for (int b = 0; b < bricks; ++b) {
      uint32_t* to = pyramid.count + pyramid.offset[1] +
                     8 * (kSegment * seg + b + pyramid.bricks[1][0] * (by + pyramid.bricks[1][1] * bz));
      uint32_t sum = 0;
      for (int c = 0; c < 8; ++c) to[c] = sum += node[2 * b + (c & 1)][c >> 1] & PyramidView::kCountMask;
    }
  }
};

// ---- 4. one reduction level (>= 2): node = sum of its 2x2x2 children ---------------------------------
/// One work item per brick of the level written: each slot's count is the last running sum of its
/// children's brick one level down (0 beyond the level's edge); the slots get their running sums.
struct ReduceLevelStage {
  PyramidView pyramid;
  int level;  // the level written (>= 2)
  SPHXR_HD void operator()(int b) const {
    const int* nb = pyramid.bricks[level];
    const int bx = b % nb[0], by = (b / nb[0]) % nb[1], bz = b / (nb[0] * nb[1]);
    uint32_t sum = 0;
    uint32_t* out = pyramid.count + pyramid.offset[level] + 8 * b;
    for (int c = 0; c < 8; ++c) {
      const int x = 2 * bx + (c & 1), y = 2 * by + ((c >> 1) & 1), z = 2 * bz + (c >> 2);
      const bool inside = x < pyramid.dims[level][0] && y < pyramid.dims[level][1] && z < pyramid.dims[level][2];
      sum += inside ? pyramid.Brick(level - 1, x, y, z)[7] : 0u;
      out[c] = sum;
    }
  }
};

// ---- 5. traversal: runs of consecutive output vertices ------------------------------------------------
/// One work item per run of `run` consecutive vertices [run * item, run * item + run) (the last run
/// ends at the apex). The first vertex walks down from the apex as in Dyken et al.: at each level the
/// children are taken in a fixed order (x fastest), skipping those whose counts lie before the
/// vertex's index, so the vertices of a cell are contiguous and in the order of its case's list. Each
/// following vertex is the next slot of the same cell, or the first slot of the next cell in that
/// order with a nonzero count: the in-order successor in the tree, found by going up from the cell
/// until a node has a later child with a nonzero count and walking down its first such children. The
/// path needs no stack: the node at level l above cell (x, y, z) is (x >> l, y >> l, z >> l) and its
/// child on the path is bit l - 1 of each coordinate. So every vertex gets exactly the cell, the slot
/// and the arithmetic of its own descent, for any run length; run = 1 is one descent per vertex (the
/// GPU's many threads), longer runs replace most descents by a step within the cell (the CPU's few
/// threads, where the ~7 dependent levels per vertex were most of the traversal's time), and a run
/// copies a vertex it computed already on the same edge instead of interpolating it again (EdgeCache).
/// A write's report as the device stores it (host-visible memory; SurfaceWriteReport is the host's copy).
struct DeviceWriteReport {
  int64_t vertices;  // the apex
  int64_t written;   // min(apex, capacity)
  int64_t capacity;
  int64_t write;     // stored last: the report is complete when the host sees the number it expects
};

struct TraverseStage {
  FieldView field;
  PyramidView pyramid;
  const int8_t* edges;  // McTables::edges on this system, kMcMaxVertices per case
  float* positions;     // xyz per vertex
  float* normals;
  const uint32_t* apex; // the mesh's vertex count, on the device (the host does not read it)
  int64_t capacity;     // vertices the target holds: the launch covers it, items past the apex return
  int run;              // vertices per work item (>= 1)
  DeviceWriteReport* report;  // host-visible; item 0 fills it
  uint64_t write;             // this write's number, stored last in the report
  uint32_t* drawCommand;      // glDrawArraysIndirect's {count, instanceCount, first, baseInstance}, or null

  /// Item 0: what the write holds, for the host (read a frame later) and for the indirect draw.
  SPHXR_HD void Report(int64_t vertices, int64_t written) const {
    if (drawCommand) {
      drawCommand[0] = static_cast<uint32_t>(written);
      drawCommand[1] = 1u;
      drawCommand[2] = 0u;
      drawCommand[3] = 0u;
    }
    report->vertices = vertices;
    report->written = written;
    report->capacity = capacity;
#if defined(__CUDA_ARCH__)
    __threadfence_system();  // the counts reach the host before the write's number does
#endif
    report->write = static_cast<int64_t>(write);
  }

  /// The child whose range of running sums holds key (the number of sums at or below it; sums are
  /// non-decreasing and the last is above key), and key made relative to that child. Branch-free, so
  /// that consecutive vertices' descents overlap in the processor. With key = the running sum up to a
  /// child, the result is its next sibling with a nonzero count (8: none).
  SPHXR_HD SPHXR_INLINE static int Select(const uint32_t sums[8], uint32_t* key) {
    const uint32_t k = *key;
    uint32_t p[8];
    for (int c = 0; c < 8; ++c) p[c] = sums[c] <= k ? 1u : 0u;
    // A tree of sums (short dependency chain), then the running sum before the child.
    const int skip = static_cast<int>(((p[0] + p[1]) + (p[2] + p[3])) + ((p[4] + p[5]) + (p[6] + p[7])));
    const uint32_t before = sums[skip > 0 ? skip - 1 : 0];
    *key = k - (skip > 0 ? before : 0u);
    return skip;
  }

  /// The running sums of the 8 cells under level-1 node (x, y, z) (a cell beyond the base's edge reads
  /// the sentinel, 0).
  SPHXR_HD SPHXR_INLINE void CellSums(int x, int y, int z, uint32_t sums[8]) const {
    const int* d = pyramid.dims[0];
    const int first = 2 * x + d[0] * (2 * y + d[1] * 2 * z);
    const bool inX = 2 * x + 1 < d[0], inY = 2 * y + 1 < d[1], inZ = 2 * z + 1 < d[2];
    uint32_t sum = 0;
    for (int k = 0; k < 8; ++k) {
      const int dx = k & 1, dy = (k >> 1) & 1, dz = k >> 2;
      const bool inside = (!dx || inX) && (!dy || inY) && (!dz || inZ);
      sum += pyramid.count[inside ? first + dx + d[0] * (dy + d[1] * dz) : pyramid.sentinel] & PyramidView::kCountMask;
      sums[k] = sum;
    }
  }

  /// Walk down from node (x, y, z) of `level` (>= 1) to the cell holding vertex `key` of that node:
  /// (x, y, z) becomes the cell, key its slot there, cellSums those of the cell's level-1 node.
  SPHXR_HD SPHXR_INLINE void Descend(int level, int* x, int* y, int* z, uint32_t* key, uint32_t cellSums[8]) const {
    for (; level > 1; --level) {
      const int skip = Select(pyramid.Brick(level - 1, *x, *y, *z), key);
      *x = 2 * *x + (skip & 1);
      *y = 2 * *y + ((skip >> 1) & 1);
      *z = 2 * *z + (skip >> 2);
    }
    CellSums(*x, *y, *z, cellSums);
    const int skip = Select(cellSums, key);
    *x = 2 * *x + (skip & 1);
    *y = 2 * *y + ((skip >> 1) & 1);
    *z = 2 * *z + (skip >> 2);
  }

  /// Vertex v: slot `key` of cell (x, y, z). The case table names the edge; the position is interpolated
  /// on it and the normal is -grad phi (central differences), interpolated the same way.
  /// The vertices a run computed last, by edge (direct-mapped on a hash of the edge's id): a vertex
  /// lies on an edge shared by up to 4 cells and by several triangles of each, and the run's cells
  /// are neighbours in the pyramid's order, so most vertices are copies of one computed a few
  /// vertices before. A copy is bitwise the value computed (every cell interpolates an edge the same
  /// way). Only runs longer than one vertex use it (the CPU's).
  struct EdgeCache {
#ifdef __CUDA_ARCH__
    static constexpr int kSize = 1;  // the GPU's runs are one vertex: no local memory for a cache
#else
    static constexpr int kSize = 64;
#endif
    static constexpr uint32_t kNone = 0xffffffffu;  // above every id (3 samples + 2 < 2^32)
    uint32_t id[kSize];
    float value[kSize][6];  // position, normal
    SPHXR_HD SPHXR_INLINE static int Slot(uint32_t id) {
      return static_cast<int>((id * 2654435761u) >> 26) & (kSize - 1);  // Knuth's multiplicative hash
    }
  };

  SPHXR_HD SPHXR_INLINE void Emit(int64_t v, int x, int y, int z, uint32_t key, EdgeCache* cache) const {
    const int* d = pyramid.dims[0];
    const int mcCase = static_cast<int>(pyramid.count[x + d[0] * (y + d[1] * z)] >> PyramidView::kCaseShift);
    const int edge = edges[mcCase * kMcMaxVertices + static_cast<int>(key)];
    // Edge 4 axis + o runs along `axis` from the cell's corner offset by (o & 1, o >> 1) on the other
    // two axes in order. Scalars, not arrays indexed by the axis: a store to one element and a load of
    // the whole stall the processor's store forwarding, per vertex.
    const int axis = edge >> 2, o = edge & 3;
    const int ax = x + (axis == 0 ? 0 : (o & 1)), ay = y + (axis == 0 ? (o & 1) : (axis == 1 ? 0 : (o >> 1)));
    const int az = z + (axis == 2 ? 0 : (o >> 1));
    const int bx = ax + (axis == 0 ? 1 : 0), by = ay + (axis == 1 ? 1 : 0), bz = az + (axis == 2 ? 1 : 0);
    const int a = field.Index(ax, ay, az);
    const uint32_t id = 3u * static_cast<uint32_t>(a) + static_cast<uint32_t>(axis);
    float* pp = positions + 3 * v;
    float* nn = normals + 3 * v;
    float* hit = nullptr;
    if (cache) {
      const int c = EdgeCache::Slot(id);
      hit = cache->value[c];
      if (cache->id[c] == id) {
        for (int i = 0; i < 3; ++i) {
          pp[i] = hit[i];
          nn[i] = hit[3 + i];
        }
        return;
      }
      cache->id[c] = id;
    }
    // From the lower corner to the upper one, so the cells sharing this edge agree bit for bit.
    const float f0 = field.value[a];
    const float f1 = field.value[field.Index(bx, by, bz)];
    const float t = (field.iso - f0) / (f1 - f0);  // f0 != f1: exactly one of them is above iso
    const Vec3 p0 = field.Point(ax, ay, az);
    const Vec3 p1 = field.Point(bx, by, bz);
    const Vec3 p = p0 + (p1 - p0) * t;
    const Vec3 g0 = field.Gradient(ax, ay, az);
    const Vec3 g1 = field.Gradient(bx, by, bz);
    const Vec3 g = g0 + (g1 - g0) * t;
    const float len = Length(g);
    // -grad phi points out of the water; a flat field (len 0) cannot say where, so take +y.
    const Vec3 n = len > 0.0f ? g * (-1.0f / len) : Vec3{0.0f, 1.0f, 0.0f};
    const float value[6] = {p.x, p.y, p.z, n.x, n.y, n.z};
    for (int i = 0; i < 3; ++i) {
      pp[i] = value[i];
      nn[i] = value[3 + i];
    }
    if (hit) {
      for (int i = 0; i < 6; ++i) hit[i] = value[i];
    }
  }

  SPHXR_HD void operator()(int64_t item) const {
    const int64_t total = *apex, room = capacity - capacity % 3;  // whole triangles
    const int64_t vertices = total < room ? total : room;
    if (item == 0) Report(total, vertices);
    const int64_t first = item * run;
    if (first >= vertices) return;
    const int64_t end = first + run < vertices ? first + run : vertices;
    uint32_t key = static_cast<uint32_t>(first);
    uint32_t cellSums[8];
    int x = 0, y = 0, z = 0;
    Descend(pyramid.levels - 1, &x, &y, &z, &key, cellSums);
    int slot = (x & 1) | ((y & 1) << 1) | ((z & 1) << 2);  // the cell in its level-1 node
    auto countOf = [&](int s) { return cellSums[s] - (s > 0 ? cellSums[s - 1] : 0u); };
    uint32_t cellCount = countOf(slot);
    EdgeCache cache;
    EdgeCache* cached = end - first > 1 ? &cache : nullptr;
    if (cached) {
      for (int i = 0; i < EdgeCache::kSize; ++i) cache.id[i] = EdgeCache::kNone;
    }
    for (int64_t v = first;;) {
      Emit(v, x, y, z, key, cached);
      if (++v == end) break;
      // The successor. Within the cell: its next slot.
      if (++key < cellCount) continue;
      // The next cell of the same level-1 node with vertices.
      uint32_t sum = cellSums[slot];
      int next = Select(cellSums, &sum);
      key = 0;
      if (next < 8) {
        x = (x & ~1) | (next & 1);
        y = (y & ~1) | ((next >> 1) & 1);
        z = (z & ~1) | (next >> 2);
        slot = next;
        cellCount = countOf(slot);
        continue;
      }
      // Up until a node has a later child with vertices (one has: v is below the apex's count), then
      // down that child's first vertices.
      int level = 2;
      for (;; ++level) {
        const int bit = level - 1;
        const uint32_t* sums = pyramid.Brick(level - 1, x >> level, y >> level, z >> level);
        const int child = ((x >> bit) & 1) | (((y >> bit) & 1) << 1) | (((z >> bit) & 1) << 2);
        sum = sums[child];
        next = Select(sums, &sum);
        if (next < 8) break;
      }
      x = 2 * (x >> level) + (next & 1);
      y = 2 * (y >> level) + ((next >> 1) & 1);
      z = 2 * (z >> level) + (next >> 2);
      Descend(level - 1, &x, &y, &z, &key, cellSums);
      slot = (x & 1) | ((y & 1) << 1) | ((z & 1) << 2);
      cellCount = countOf(slot);
    }
  }
};

}  // namespace sphxr::sim
