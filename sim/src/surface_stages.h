#pragma once
// The stages of histogram-pyramid marching cubes (Dyken, Ziegler, Theobalt, Seidel 2008, "High-speed
// marching cubes using histogram pyramids"), written once as host+device functors over raw pointers.
// surface_impl.h launches them with thrust on the OpenMP system (CPU backend) or the CUDA system.
//
//   1. bounds     the fluid's bounding box (a reduction); the sample lattice covers it plus a margin
//   2. near       per neighbour-grid cell under the lattice: is any fluid particle in its 27 cells?
//   3. field      phi at every sample, gathered through the neighbour grid's cellStart/cellEnd, one
//                 work item per neighbour cell for the samples in it; a block that is not near is
//                 written as zeros without reading a particle
//   4. base       level 0 of the pyramid: the vertex count of each cell's marching-cubes case
//   5. reduce     level l node = sum of its 2x2x2 children in level l-1, up to the apex (the total)
//   6. traverse   one thread per output vertex: walk down from the apex, at each level skipping the
//                 children whose counts lie before the vertex's index, to its cell and the vertex's
//                 slot there; the case table names the edge; the position is interpolated on it and the
//                 normal is -grad phi (central differences), interpolated the same way.
// No per-cell output buffer of the worst-case size exists: the mesh has exactly apex vertices.
#include <cstdint>

#include "kernel.h"
#include "mc_tables.h"
#include "sphxr/sim/hd.h"
#include "sphxr/sim/surface.h"
#include "sphxr/sim/vec.h"
#include "stages.h"

namespace sphxr::sim {

inline constexpr int kMaxPyramidLevels = 32;

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

// ---- 2. near flags: neighbour-grid cells [c0, c0 + n) that have fluid in their 27 cells ----------
struct NearCellsStage {
  GridView grid;
  int c0x, c0y, c0z;
  int nx, ny;  // extent of the flagged block (nz implied by the launch size)
  uint8_t* near;
  SPHXR_HD void operator()(int b) const {
    const int cx = c0x + b % nx, cy = c0y + (b / nx) % ny, cz = c0z + b / (nx * ny);
    uint8_t any = 0;
    for (int z = cz - 1; z <= cz + 1 && !any; ++z)
      for (int y = cy - 1; y <= cy + 1; ++y)
        for (int x = cx - 1; x <= cx + 1; ++x) {
          if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz) continue;
          if (grid.fluidStart[grid.Linear(x, y, z)] != kEmptyCell) any = 1;
        }
    near[b] = any;
  }
};

// ---- 3. the field: phi(x) = sum_j V W(|x - x_j|), V = m / rho0 --------------------------------------
/// One neighbour-grid cell of the near block: the samples whose cell (GridView::CellOf) it is share
/// their 27 candidate cells, so the candidates are read once for all of them, and each candidate is
/// tested against the samples' planes, rows and points in turn (a plane beyond the support skips its
/// rows). Per sample the particles are summed in the order of ForEachInCells (z, y, x, then the cell's
/// range), so the value is the same as a per-sample gather. A block of more than kMaxBlock samples along
/// an axis (cells much finer than the support) gathers sample by sample.
struct FieldStage {
  static constexpr int kMaxBlock = 8;
  GridView grid;
  const Vec4* position;  // sorted fluid positions (the grid's cell ranges index them)
  CubicSpline kernel;
  float volume;          // m / rho0 = dx^3
  FieldView field;
  int c0x, c0y, c0z, nearNx, nearNy;
  const uint8_t* near;
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

  SPHXR_HD void operator()(int b) const {
    const int cx = c0x + b % nearNx, cy = c0y + (b / nearNx) % nearNy, cz = c0z + b / (nearNx * nearNy);
    int i0, ni, j0, nj, k0, nk;
    AxisRange(cx, grid.nx, grid.origin.x, grid.invCellSize, grid.cellSize, field.origin.x, field.cellSize, field.nx, &i0, &ni);
    AxisRange(cy, grid.ny, grid.origin.y, grid.invCellSize, grid.cellSize, field.origin.y, field.cellSize, field.ny, &j0, &nj);
    AxisRange(cz, grid.nz, grid.origin.z, grid.invCellSize, grid.cellSize, field.origin.z, field.cellSize, field.nz, &k0, &nk);
    if (ni <= 0 || nj <= 0 || nk <= 0) return;
    if (!near[b]) {
      for (int k = 0; k < nk; ++k)
        for (int j = 0; j < nj; ++j)
          for (int i = 0; i < ni; ++i) out[field.Index(i0 + i, j0 + j, k0 + k)] = 0.0f;
      return;
    }
    const CubicSpline w = kernel;
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
    float xs[kMaxBlock], ys[kMaxBlock], zs[kMaxBlock];
    for (int i = 0; i < ni; ++i) xs[i] = field.origin.x + static_cast<float>(i0 + i) * field.cellSize;
    for (int j = 0; j < nj; ++j) ys[j] = field.origin.y + static_cast<float>(j0 + j) * field.cellSize;
    for (int k = 0; k < nk; ++k) zs[k] = field.origin.z + static_cast<float>(k0 + k) * field.cellSize;
    float sum[kMaxBlock * kMaxBlock * kMaxBlock];
    for (int s = 0; s < ni * nj * nk; ++s) sum[s] = 0.0f;
    const int z0 = cz > 0 ? cz - 1 : 0, z1 = cz < grid.nz - 1 ? cz + 1 : cz;
    const int y0 = cy > 0 ? cy - 1 : 0, y1 = cy < grid.ny - 1 ? cy + 1 : cy;
    const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx < grid.nx - 1 ? cx + 1 : cx;
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const uint32_t c = grid.Linear(x, y, z);
          const uint32_t s0 = grid.fluidStart[c];
          if (s0 == kEmptyCell) continue;
          const uint32_t s1 = grid.fluidEnd[c];
          for (uint32_t p = s0; p < s1; ++p) {
            const Vec4 q = position[p];
            for (int k = 0; k < nk; ++k) {
              const float dz = zs[k] - q.z, dz2 = dz * dz;
              if (dz2 >= w.H2) continue;
              for (int j = 0; j < nj; ++j) {
                const float dy = ys[j] - q.y, dyz2 = dz2 + dy * dy;
                if (dyz2 >= w.H2) continue;
                float* row = sum + (k * nj + j) * ni;
                for (int i = 0; i < ni; ++i) {
                  const float dx = xs[i] - q.x, r2 = dyz2 + dx * dx;
                  if (r2 < w.H2) row[i] += w.W(sqrtf(r2));
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
/// dimension (rounding up) until the apex, a single node. Level 0 is linear (x fastest; exactly one
/// count per cell, then one zero, the sentinel that children beyond the base's edge read). Levels
/// above are stored in 2x2x2 bricks (node (x, y, z) in brick (x/2, y/2, z/2), slot x&1 + 2 (y&1) +
/// 4 (z&1); slots beyond a level's edge hold 0), so the 8 children of a node of level >= 2 are 32
/// contiguous bytes. Padding only the small upper levels keeps the pyramid within ~1.15x its base.
struct PyramidView {
  int levels;
  int dims[kMaxPyramidLevels][3];    // nodes per axis
  int bricks[kMaxPyramidLevels][3];  // ceil(dims / 2), levels >= 1
  int offset[kMaxPyramidLevels];
  int sentinel;                      // index of a 0 (after the base level)
  uint32_t* count;

  /// Level >= 1: the node of slot n (n in [0, 8 * bricks)); false for a padding slot.
  SPHXR_HD SPHXR_INLINE bool Decode(int level, int n, int* x, int* y, int* z) const {
    const int b = n >> 3, sub = n & 7;
    const int bx = b % bricks[level][0], by = (b / bricks[level][0]) % bricks[level][1];
    const int bz = b / (bricks[level][0] * bricks[level][1]);
    *x = 2 * bx + (sub & 1);
    *y = 2 * by + ((sub >> 1) & 1);
    *z = 2 * bz + (sub >> 2);
    return *x < dims[level][0] && *y < dims[level][1] && *z < dims[level][2];
  }
  /// The counts of the 8 children of node (x, y, z) of `level` (>= 1), x fastest; 0 beyond an edge.
  SPHXR_HD SPHXR_INLINE void Children(int level, int x, int y, int z, uint32_t n[8]) const {
    if (level >= 2) {
      const uint32_t* c = count + offset[level - 1] + 8 * (x + bricks[level - 1][0] * (y + bricks[level - 1][1] * z));
      for (int k = 0; k < 8; ++k) n[k] = c[k];
      return;
    }
    const int* d = dims[0];
    const int first = 2 * x + d[0] * (2 * y + d[1] * 2 * z);
    const bool inX = 2 * x + 1 < d[0], inY = 2 * y + 1 < d[1], inZ = 2 * z + 1 < d[2];
    for (int k = 0; k < 8; ++k) {
      const int dx = k & 1, dy = (k >> 1) & 1, dz = k >> 2;
      const bool inside = (!dx || inX) && (!dy || inY) && (!dz || inZ);
      n[k] = count[inside ? first + dx + d[0] * (dy + d[1] * dz) : sentinel];
    }
  }
};

SPHXR_HD SPHXR_INLINE int McCase(const FieldView& f, int i, int j, int k) {
  int mask = 0;
  for (int c = 0; c < 8; ++c) {
    const float v = f.value[f.Index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
    if (v > f.iso) mask |= 1 << c;
  }
  return mask;
}

// ---- 4. base level: vertices of each cell's case ---------------------------------------------------
struct BaseLevelStage {
  FieldView field;
  PyramidView pyramid;
  const uint8_t* vertexCount;  // McTables::vertexCount on this system
  SPHXR_HD void operator()(int c) const {
    const int cnx = field.nx - 1, cny = field.ny - 1;
    const int i = c % cnx, j = (c / cnx) % cny, k = c / (cnx * cny);
    pyramid.count[c] = vertexCount[McCase(field, i, j, k)];
  }
};

// ---- 5. one reduction level: node = sum of its 2x2x2 children ----------------------------------------
struct ReduceLevelStage {
  PyramidView pyramid;
  int level;  // the level written (>= 1)
  SPHXR_HD void operator()(int n) const {
    int x, y, z;
    uint32_t sum = 0;
    if (pyramid.Decode(level, n, &x, &y, &z)) {
      uint32_t child[8];
      pyramid.Children(level, x, y, z, child);
      for (int c = 0; c < 8; ++c) sum += child[c];
    }
    pyramid.count[pyramid.offset[level] + n] = sum;
  }
};

// ---- 6. traversal: one thread per output vertex ------------------------------------------------------
struct TraverseStage {
  FieldView field;
  PyramidView pyramid;
  const int8_t* edges;  // McTables::edges on this system, kMcMaxVertices per case
  float* positions;     // xyz per vertex
  float* normals;
  SPHXR_HD void operator()(int64_t v) const {
    // Walk down: at each level the children are taken in a fixed order (x fastest), so the vertices
    // of a cell are contiguous and in the order of its case's list. Branch-free: the 8 counts (one
    // brick above the base), their running sums, and the number of children that end at or before the key.
    uint32_t key = static_cast<uint32_t>(v);
    int x = 0, y = 0, z = 0;
    for (int level = pyramid.levels - 1; level > 0; --level) {
      uint32_t n[8];
      pyramid.Children(level, x, y, z, n);
      uint32_t sum = 0, before = 0;
      int skip = 0;
      for (int c = 0; c < 8; ++c) {
        sum += n[c];
        const bool past = sum <= key;
        skip += past ? 1 : 0;
        before = past ? sum : before;
      }
      key -= before;
      x = 2 * x + (skip & 1);
      y = 2 * y + ((skip >> 1) & 1);
      z = 2 * z + (skip >> 2);
    }
    // (x, y, z) is the cell, key the vertex's slot in its case's list.
    const int mcCase = McCase(field, x, y, z);
    const int edge = edges[mcCase * kMcMaxVertices + static_cast<int>(key)];
    const int axis = edge / 4, o = edge % 4;
    int a[3] = {x, y, z};
    if (axis == 0) { a[1] += o & 1; a[2] += o >> 1; }
    else if (axis == 1) { a[0] += o & 1; a[2] += o >> 1; }
    else { a[0] += o & 1; a[1] += o >> 1; }
    int b[3] = {a[0], a[1], a[2]};
    b[axis] += 1;
    // From the lower corner to the upper one, so the cells sharing this edge agree bit for bit.
    const float f0 = field.value[field.Index(a[0], a[1], a[2])];
    const float f1 = field.value[field.Index(b[0], b[1], b[2])];
    const float t = (field.iso - f0) / (f1 - f0);  // f0 != f1: exactly one of them is above iso
    const Vec3 p0 = field.Point(a[0], a[1], a[2]);
    const Vec3 p1 = field.Point(b[0], b[1], b[2]);
    const Vec3 p = p0 + (p1 - p0) * t;
    const Vec3 g0 = field.Gradient(a[0], a[1], a[2]);
    const Vec3 g1 = field.Gradient(b[0], b[1], b[2]);
    const Vec3 g = g0 + (g1 - g0) * t;
    const float len = Length(g);
    // -grad phi points out of the water; a flat field (len 0) cannot say where, so take +y.
    const Vec3 n = len > 0.0f ? g * (-1.0f / len) : Vec3{0.0f, 1.0f, 0.0f};
    float* pp = positions + 3 * v;
    float* nn = normals + 3 * v;
    pp[0] = p.x;
    pp[1] = p.y;
    pp[2] = p.z;
    nn[0] = n.x;
    nn[1] = n.y;
    nn[2] = n.z;
  }
};

}  // namespace sphxr::sim
