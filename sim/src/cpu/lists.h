#pragma once
// The SIMD traversals of a particle's neighbour list and of the wall particles of its cells, kLanes at a
// time, shared by the passes that work from the density stage's lists (position-based fluids' passes,
// solvers/pbf/pbf_simd.h; DFSPH's factor and solve, solvers/dfsph/dfsph_simd.h), and the lane-blocked
// pair cache's loads and stores.
#include <cstdint>
#include <cstring>

#include "cpu/simd.h"
#include "stages.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

/// The lanes of particle i's list: up to kLanes entries from `base`, lanes past the end set to i itself
/// (masked off by the pair test, which excludes j == i as ForEachOther does). With AVX-512 and AVX one
/// masked load (the lanes past `found` are not read: a list's last batch may end past the list's
/// allocation); else entry by entry.
SPHXR_INLINE LaneInts ListLanes(const uint32_t* slots, uint32_t base, uint32_t found, int i) {
  const uint32_t left = found - base;  // > 0
#if defined(__AVX512F__) && defined(__AVX512DQ__)
  const __mmask16 m = left >= 16u ? static_cast<__mmask16>(0xffff) : static_cast<__mmask16>((1u << left) - 1u);
  const __m512i v = _mm512_mask_loadu_epi32(_mm512_set1_epi32(i), m, slots + base);
  LaneInts index;
  std::memcpy(&index, &v, sizeof index);
  return index;
#elif defined(__AVX__)
  const __m256 m = _mm256_cmp_ps(_mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f),
                                 _mm256_set1_ps(static_cast<float>(left < 8u ? left : 8u)), _CMP_LT_OQ);
  const __m256 loaded = _mm256_maskload_ps(reinterpret_cast<const float*>(slots + base), _mm256_castps_si256(m));
  const __m256 v = _mm256_blendv_ps(_mm256_castsi256_ps(_mm256_set1_epi32(i)), loaded, m);
  LaneInts index;
  std::memcpy(&index, &v, sizeof index);
  return index;
#else
  LaneInts index;
  for (int l = 0; l < kLanes; ++l) {
    index[l] = static_cast<int32_t>(static_cast<uint32_t>(l) < left ? slots[base + l] : static_cast<uint32_t>(i));
  }
  return index;
#endif
}

/// Particle i's row of a lane-blocked pair cache (PairCacheStride floats a particle): the passes of PBF
/// and DFSPH that keep each listed pair's V grad W_ij for the passes after them (solvers/pbf/pbf_simd.h,
/// solvers/dfsph/dfsph_simd.h).
SPHXR_INLINE float* PairCacheRow(float* cache, int stride, int i) {
  SPHXR_ASSERT(cache);  // the CPU launcher's kPairCache
  return cache + static_cast<size_t>(i) * static_cast<size_t>(stride);
}

/// Stores batch `batch` of a row: kLanes x, then kLanes y, then kLanes z.
SPHXR_INLINE void StorePairBatch(float* row, int batch, Lanes x, Lanes y, Lanes z) {
  float* out = row + 3 * kLanes * batch;
  std::memcpy(out, &x, sizeof x);
  std::memcpy(out + kLanes, &y, sizeof y);
  std::memcpy(out + 2 * kLanes, &z, sizeof z);
}

/// f(index, gx, gy, gz) for particle i's listed neighbours kLanes at a time with their cached V grad W_ij
/// (the row's batches; the lanes past the list's end hold i itself and a zero gradient).
template <class F>
SPHXR_INLINE void ForCachedPairs(const NeighbourList& list, const float* row, int i, F&& f) {
  const uint32_t found = list.count[i];
  const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
  for (uint32_t base = 0; base < found; base += kLanes, row += 3 * kLanes) {
    Lanes gx, gy, gz;
    std::memcpy(&gx, row, sizeof gx);
    std::memcpy(&gy, row + kLanes, sizeof gy);
    std::memcpy(&gz, row + 2 * kLanes, sizeof gz);
    f(ListLanes(slots, base, found, i), gx, gy, gz);
  }
}

/// Whether particle i's list overflowed (the scalar stage then scans its cells).
SPHXR_INLINE bool Overflowed(const NeighbourList& list, int i) {
  return list.count[i] > static_cast<uint32_t>(list.maxNeighbours);
}

/// f(index, dx, dy, dz, r, q, pair, batch) for particle i's listed fluid neighbours kLanes at a time:
/// d = x_i - x_j, r = |d|, q = r / H, `pair` the lanes within the support other than i itself, `batch`
/// the batch's number in the list. Batches with no pair are skipped unless `everyBatch`.
template <class F>
SPHXR_INLINE void ForListLanes(const NeighbourList& list, const FluidView& fluid, const CubicSpline& k, int i, Vec3 xi,
                               F&& f, bool everyBatch = false) {
  const uint32_t found = list.count[i];
  const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
  const float* position = reinterpret_cast<const float*>(fluid.position);  // Vec4: x y z w
  const LaneInts self = LaneInts{} + i;
  int batch = 0;
  for (uint32_t base = 0; base < found; base += kLanes, ++batch) {
    const LaneInts index = ListLanes(slots, base, found, i);
    Lanes xj, yj, zj;
    GatherXyz(position, index, &xj, &yj, &zj);
    const Lanes dx = xi.x - xj, dy = xi.y - yj, dz = xi.z - zj;
    const Lanes r2 = dx * dx + dy * dy + dz * dz;
    const LaneInts pair = And(Less(r2, Splat(k.H2)), index != self);
    if (!everyBatch && Bits(pair) == 0) continue;
    const Lanes r = Sqrt(r2);
    f(index, dx, dy, dz, r, r * k.invH, pair, batch);
  }
}

/// The lanes l < n as a mask.
SPHXR_INLINE LaneInts FirstLanes(int n) {
  Lanes laneNumber;
  for (int l = 0; l < kLanes; ++l) laneNumber[l] = static_cast<float>(l);
  return Less(laneNumber, Splat(static_cast<float>(n)));
}

/// f(dx, dy, dz, r, q, psi, pair) for the wall particles of xi's cells kLanes at a time, where the cell is
/// near a wall (the scalar ForEachBoundaryNear's test): d = x_i - x_b, psi = Psi_b, `pair` the lanes
/// within the support (batches with none skipped).
template <class F>
SPHXR_INLINE void ForWallLanes(const GridView& g, const CubicSpline& k, Vec3 xi, F&& f) {
  int cx, cy, cz;
  g.CellOf(xi, &cx, &cy, &cz);
  if (!g.boundaryNear[g.Linear(cx, cy, cz)]) return;
  const float* boundary = reinterpret_cast<const float*>(g.boundary);  // Vec4: x y z Psi
  LaneInts index;
  int n = 0;
  auto flush = [&]() {
    for (int l = n; l < kLanes; ++l) index[l] = index[0];  // padding, masked off below
    Lanes xb, yb, zb, psi;
    GatherXyzw(boundary, index, &xb, &yb, &zb, &psi);
    const Lanes dx = xi.x - xb, dy = xi.y - yb, dz = xi.z - zb;
    const Lanes r2 = dx * dx + dy * dy + dz * dz;
    const LaneInts pair = And(Less(r2, Splat(k.H2)), FirstLanes(n));
    n = 0;
    if (Bits(pair) == 0) return;
    const Lanes r = Sqrt(r2);
    f(dx, dy, dz, r, r * k.invH, psi, pair);
  };
  ForEachInCells(g, g.boundaryStart, g.boundaryEnd, g.boundary, xi, [&](uint32_t b, Vec3) {
    index[n++] = static_cast<int32_t>(b);
    if (n == kLanes) flush();
  });
  if (n > 0) flush();
}

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
