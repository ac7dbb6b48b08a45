#pragma once
// The CPU backend's SIMD traversals of the density and force stages (host-only; the CUDA backend runs
// stages.h's DensityStage and ForceStage, a thread per particle). The physics is stages.h's: these
// only arrange the same sums for vector units (kLanes wide: 8 with AVX, else 16; see kLanes).
//
// Density (DensityBlockStage): one work item per block of up to kLanes particles of one box of grid cells
// (particles are sorted by Morton code, so a Morton-aligned box is a contiguous run: a pair of cells along
// x where the water is dense, up to 4 x 4 x 4 cells in spray; BlockBoxOf). Each candidate j of the cells around
// the block is loaded once and evaluated for all the block's particles at once: the distance, the hit
// mask, sqrt and the kernel (both pieces, selected per lane); the neighbour-list appends are scalar
// (kVectorAppends: on AVX and AVX-512 without a branch per hit). The per-particle DensityStage does the same one
// candidate and one particle at a time, with a branch per candidate and per kernel piece. Same cells, same candidate order: each
// particle's sum adds the same terms in the same order and its neighbour list is the same list; a
// kernel value may differ in the last bit where the compiler fuses a multiply-add differently.
//
// Forces (ForceListStage): per particle, its neighbour list kLanes at a time, the neighbours' fields
// loaded into vectors (GatherXyz, Gather), the pair terms of ForceStage in every lane, the lanes summed at the end. The
// sum's order differs from ForceStage's serial one (rounding only). The wall terms are summed the same
// way, kLanes wall particles at a time from the particle's cells; the bodies, gravity and the reuse
// guard are ForceStage::Store itself.
//
// Walls: the density blocks take the walls' kernel sums like the fluid's (each lane's terms in its own
// scan's order), and WallPressureBlockStage the wall particles of one cell kLanes at a time.
//
// All are deterministic for any thread count (a particle's sums never depend on the schedule), and
// the CPU runs them for every density and force evaluation, with reuse too (DensityBlockStage's
// blocks then drawn from the particles that compute, BlockSet; masked lanes only for the pairs-only
// layout), so reuse off and reuse with IDLE = 0 stay bit-identical. tests/sim/cpu_stages_test.cpp compares each with the per-particle stages and with
// brute force.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
#include <immintrin.h>
#endif

#include "morton.h"
#include "stages.h"

// Each instruction-set tier gets its own inline namespace: a translation unit built for another tier
// (a test without -march=native) then cannot lend its copies of these inline functions to the backend's.
#if defined(__AVX512F__) && defined(__AVX512DQ__)
#define SPHXR_CPU_TIER cpu_avx512
#elif defined(__AVX__)
#define SPHXR_CPU_TIER cpu_avx
#elif defined(__SSE2__)
#define SPHXR_CPU_TIER cpu_sse2
#else
#define SPHXR_CPU_TIER cpu_scalar
#endif

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

// Lanes per SIMD value: one register of the widest unit where there is one (AVX-512 with DQ: 16;
// AVX or AVX2, and AVX-512 without DQ: 8), else 16 in four SSE2 registers or in scalars. Measured on an AVX2 machine (docs/design/simd_stages.md,
// "AVX2 machines"): 16 lanes in two 256-bit halves left the values spilling (16 ymm registers hold
// eight of them) and every comparison, select and gather split in two; eight lanes in one register
// made the whole step 1.23-1.4x faster, although a density block then holds 8 particles instead of 16.
#if defined(__AVX512F__) && defined(__AVX512DQ__)
inline constexpr int kLanes = 16;
#define SPHXR_LANE_BYTES 64
#elif defined(__AVX__)
inline constexpr int kLanes = 8;
#define SPHXR_LANE_BYTES 32
#else
inline constexpr int kLanes = 16;
#define SPHXR_LANE_BYTES 64
#endif

/// The density blocks' neighbour-list appends: branch-free into scratch lists (a store per lane per
/// candidate that hits, the counts in a vector) in the AVX and AVX-512 tiers, where it made the density
/// stage 1.2-1.3x faster on an AVX2 machine and 1.05-1.1x on an AVX-512 machine; one store
/// per hit in the SSE2 and scalar tiers. In the SSE2 tier's 16 lanes (four registers) the vector counts
/// made the stage 1.15-1.35x slower (docs/design/simd_stages.md).
#if defined(__AVX__)
inline constexpr bool kVectorAppends = true;
#else
inline constexpr bool kVectorAppends = false;
#endif

/// kLanes floats (ints) in one SIMD value (GCC/Clang vector extension).
typedef float Lanes __attribute__((vector_size(SPHXR_LANE_BYTES), aligned(SPHXR_LANE_BYTES)));
typedef int32_t LaneInts __attribute__((vector_size(SPHXR_LANE_BYTES), aligned(SPHXR_LANE_BYTES)));
static_assert(sizeof(Lanes) == kLanes * sizeof(float));

inline Lanes Splat(float v) { return Lanes{} + v; }

inline Lanes Sqrt(Lanes a) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
  // (Zero-masked with all lanes on: GCC 12's _mm512_sqrt_ps passes an undefined merge source that
  // -Wmaybe-uninitialized reports at every use.)
  return reinterpret_cast<Lanes>(_mm512_maskz_sqrt_ps(static_cast<__mmask16>(0xffff), reinterpret_cast<__m512>(a)));
#elif defined(__AVX__)
  return reinterpret_cast<Lanes>(_mm256_sqrt_ps(reinterpret_cast<__m256>(a)));
#elif defined(__SSE2__)
  __m128 h[4];
  std::memcpy(h, &a, sizeof a);
  for (int k = 0; k < 4; ++k) h[k] = _mm_sqrt_ps(h[k]);
  std::memcpy(&a, h, sizeof a);
  return a;
#else
  for (int l = 0; l < kLanes; ++l) a[l] = std::sqrt(a[l]);
  return a;
#endif
}

/// Bit l set where the comparison result (all ones / zero per lane) is true.
inline uint32_t Bits(LaneInts c) {
#if defined(__AVX512DQ__)
  return static_cast<uint32_t>(_mm512_movepi32_mask(reinterpret_cast<__m512i>(c)));
#elif defined(__AVX__)
  return static_cast<uint32_t>(_mm256_movemask_ps(reinterpret_cast<__m256>(c)));
#elif defined(__SSE2__)
  __m128 h[4];
  std::memcpy(h, &c, sizeof c);
  uint32_t m = 0;
  for (int k = 0; k < 4; ++k) m |= static_cast<uint32_t>(_mm_movemask_ps(h[k])) << (4 * k);
  return m;
#else
  uint32_t m = 0;
  for (int l = 0; l < kLanes; ++l) m |= (c[l] != 0 ? 1u : 0u) << l;
  return m;
#endif
}

/// Lane-wise comparisons (all ones where true), a bitwise and of two masks, and a select. Where a value
/// is one register (AVX-512, AVX) the float operators are one instruction each (AVX without AVX2
/// splits the integer ones, a cost in speed only). In the SSE2 tier's
/// four registers GCC 12 lowers a comparison or a ?: lane by lane (a scalar compare, a store of each
/// 32-bit result, then a 128-bit reload that the store buffer cannot forward; measured on an AVX2 machine
/// with 16 lanes in two halves, that made the density and force stages 2-3x slower), so that tier
/// compares and selects per quarter with the intrinsics. Same NaN semantics as the operators: <, <= are
/// ordered (false for NaN), != is unordered (true for NaN); the results are bit for bit the operators'.
#if defined(__SSE2__) && !defined(__AVX__)
template <class Op>
inline LaneInts Quarters(Lanes a, Lanes b, Op op) {
  __m128 x[4], y[4];
  std::memcpy(x, &a, sizeof a);
  std::memcpy(y, &b, sizeof b);
  for (int k = 0; k < 4; ++k) x[k] = op(x[k], y[k]);
  LaneInts out;
  std::memcpy(&out, x, sizeof out);
  return out;
}
inline LaneInts Less(Lanes a, Lanes b) { return Quarters(a, b, [](__m128 x, __m128 y) { return _mm_cmplt_ps(x, y); }); }
inline LaneInts LessEq(Lanes a, Lanes b) { return Quarters(a, b, [](__m128 x, __m128 y) { return _mm_cmple_ps(x, y); }); }
inline LaneInts NotEq(Lanes a, Lanes b) { return Quarters(a, b, [](__m128 x, __m128 y) { return _mm_cmpneq_ps(x, y); }); }
inline LaneInts And(LaneInts a, LaneInts b) { return a & b; }
inline Lanes Select(LaneInts m, Lanes a, Lanes b) {
  __m128 mm[4], x[4], y[4];
  std::memcpy(mm, &m, sizeof m);
  std::memcpy(x, &a, sizeof a);
  std::memcpy(y, &b, sizeof b);
  for (int k = 0; k < 4; ++k) x[k] = _mm_or_ps(_mm_and_ps(mm[k], x[k]), _mm_andnot_ps(mm[k], y[k]));
  Lanes out;
  std::memcpy(&out, x, sizeof out);
  return out;
}
#else
inline LaneInts Less(Lanes a, Lanes b) { return a < b; }
inline LaneInts LessEq(Lanes a, Lanes b) { return a <= b; }
inline LaneInts NotEq(Lanes a, Lanes b) { return a != b; }
inline LaneInts And(LaneInts a, LaneInts b) { return a & b; }
inline Lanes Select(LaneInts m, Lanes a, Lanes b) { return m ? a : b; }
#endif

/// Gathers base[index[l]] into lane l (scalar loads put together; no tier uses a gather instruction).
inline Lanes Gather(const float* base, LaneInts index) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
  // Sixteen loads put together in registers, not the gather instruction: on an AVX-512 machine
  // the force stage is 1.1x faster so (docs/design/simd_stages.md).
  return reinterpret_cast<Lanes>(_mm512_set_ps(base[index[15]], base[index[14]], base[index[13]], base[index[12]],
                                               base[index[11]], base[index[10]], base[index[9]], base[index[8]],
                                               base[index[7]], base[index[6]], base[index[5]], base[index[4]],
                                               base[index[3]], base[index[2]], base[index[1]], base[index[0]]));
#elif defined(__AVX__)
  // Eight loads put together in registers, not AVX2's gather instruction: on an AVX2 machine the
  // force stage is 1.1-1.15x faster so (docs/design/simd_stages.md).
  return reinterpret_cast<Lanes>(_mm256_set_ps(base[index[7]], base[index[6]], base[index[5]], base[index[4]],
                                               base[index[3]], base[index[2]], base[index[1]], base[index[0]]));
#else
  Lanes out;
  for (int l = 0; l < kLanes; ++l) out[l] = base[index[l]];
  return out;
#endif
}

/// x, y, z (and w, where asked for) of the Vec4s base[index[l]] (base: x y z w per point) into lane l:
/// the same values as Gathers of base, base + 1, ... at index * 4. On AVX the eight points are loaded
/// whole (16 bytes each, two to a register) and transposed in registers, 8 loads and 7-8 shuffles instead
/// of three or four gather instructions, whose latency the force loop waited on (AVX2: the force
/// stage 1.6-2x faster, docs/design/simd_stages.md). AVX-512 does the same with 16 points,
/// four to a register (AVX-512: the force stage 1.5x faster).
SPHXR_INLINE void GatherXyzw(const float* base, LaneInts index, Lanes* x, Lanes* y, Lanes* z, Lanes* w) {
#if defined(__AVX__) && !defined(__AVX512DQ__)
  auto row = [&](int l) {  // points l and l + 4 in the low and high halves
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(base + 4 * static_cast<std::ptrdiff_t>(index[l]))),
                                _mm_loadu_ps(base + 4 * static_cast<std::ptrdiff_t>(index[l + 4])), 1);
  };
  const __m256 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  // Per 128-bit half (points 0-3 low, 4-7 high): t0 = x0 x1 y0 y1 | x4 x5 y4 y5, t1 = x2 x3 y2 y3 | ...,
  // t2 = z0 z1 w0 w1 | z4 z5 w4 w5, t3 = z2 z3 w2 w3 | ...; the shuffles take a pair from each.
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpacklo_ps(r2, r3);
  const __m256 t2 = _mm256_unpackhi_ps(r0, r1), t3 = _mm256_unpackhi_ps(r2, r3);
  *x = reinterpret_cast<Lanes>(_mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0)));
  *y = reinterpret_cast<Lanes>(_mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2)));
  *z = reinterpret_cast<Lanes>(_mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0)));
  if (w) *w = reinterpret_cast<Lanes>(_mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2)));
#elif defined(__AVX512F__) && defined(__AVX512DQ__)
  auto point = [&](int l) { return _mm_loadu_ps(base + 4 * static_cast<std::ptrdiff_t>(index[l])); };
  auto row = [&](int l) {  // points l, l + 4, l + 8, l + 12 in the four 128-bit quarters
    __m512 r = _mm512_zextps128_ps512(point(l));
    r = _mm512_insertf32x4(r, point(l + 4), 1);
    r = _mm512_insertf32x4(r, point(l + 8), 2);
    return _mm512_insertf32x4(r, point(l + 12), 3);
  };
  const __m512 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  // (Zero-masked with all lanes on: GCC 12's _mm512_unpack*_ps and _mm512_shuffle_ps pass an undefined
  // merge source, as in Sqrt.)
  const __mmask16 all = 0xffff;
  const __m512 t0 = _mm512_maskz_unpacklo_ps(all, r0, r1), t1 = _mm512_maskz_unpacklo_ps(all, r2, r3);
  const __m512 t2 = _mm512_maskz_unpackhi_ps(all, r0, r1), t3 = _mm512_maskz_unpackhi_ps(all, r2, r3);
  *x = reinterpret_cast<Lanes>(_mm512_maskz_shuffle_ps(all, t0, t1, _MM_SHUFFLE(1, 0, 1, 0)));
  *y = reinterpret_cast<Lanes>(_mm512_maskz_shuffle_ps(all, t0, t1, _MM_SHUFFLE(3, 2, 3, 2)));
  *z = reinterpret_cast<Lanes>(_mm512_maskz_shuffle_ps(all, t2, t3, _MM_SHUFFLE(1, 0, 1, 0)));
  if (w) *w = reinterpret_cast<Lanes>(_mm512_maskz_shuffle_ps(all, t2, t3, _MM_SHUFFLE(3, 2, 3, 2)));
#else
  const LaneInts at = index * 4;
  *x = Gather(base, at);
  *y = Gather(base + 1, at);
  *z = Gather(base + 2, at);
  if (w) *w = Gather(base + 3, at);
#endif
}
SPHXR_INLINE void GatherXyz(const float* base, LaneInts index, Lanes* x, Lanes* y, Lanes* z) {
  GatherXyzw(base, index, x, y, z, nullptr);
}

/// The sum of the lanes, in lane order.
inline float SumLanes(Lanes v) {
  float s = 0.0f;
  for (int l = 0; l < kLanes; ++l) s += v[l];
  return s;
}

/// CubicSpline::W(r) (kernel.h) in every lane from q = r / H: both pieces, each lane's own, and 0 where
/// `valid` is off or q >= 1.
inline Lanes KernelWLanes(const CubicSpline& k, Lanes q, LaneInts valid) {
  const Lanes t = 1.0f - q;
  const Lanes w = Select(LessEq(q, Splat(0.5f)), k.sigma * (6.0f * (q * q * q - q * q) + 1.0f),
                             k.sigma * 2.0f * t * t * t);
  return Select(And(valid, Less(q, Splat(1.0f))), w, Splat(0.0f));
}

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

/// CubicSpline::GradFactor in every lane from q = r / H and r (0 where `pair` is off or q >= 1; r > 0
/// where it is used).
inline Lanes GradFactorLanes(const CubicSpline& k, Lanes q, Lanes r, LaneInts pair) {
  const Lanes t = 1.0f - q;
  return Select(And(pair, Less(q, Splat(1.0f))),
                  Select(LessEq(q, Splat(0.5f)), k.gradA * (3.0f * q - 2.0f), -k.gradB * t * t / r), Splat(0.0f));
}

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
    const uint32_t capacity = static_cast<uint32_t>(stage.list.maxNeighbours);
    uint32_t found[kLanes] = {};
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
    // The walls: the lanes whose own cell has a wall particle in its 27 cells (WallSum's test); the
    // others keep 0, as WallSum gives them.
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
    for (int l = 0; l < lanes; ++l) {
      if (computing & (1u << l)) {
        stage.Complete(static_cast<int>(particle[l]), Vec3{px[l], py[l], pz[l]}, sum[l], wall[l], found[l]);
      }
    }
  }
};

/// ForceStage for particle i with its fluid neighbours summed kLanes at a time from the neighbour list
/// (a list that overflowed falls back to ForceStage's own cell scan), and its wall particles kLanes at
/// a time from its cells (ForceStage::End's wall terms).
struct ForceListStage {
  ForceStage stage;

  void operator()(int i) const {
    const uint32_t found = stage.list.count[i];
    const uint32_t capacity = static_cast<uint32_t>(stage.list.maxNeighbours);
    if (found > capacity) {
      stage(i);
      return;
    }
    ForceParticle P = stage.Begin(i);
    const FluidView& f = stage.fluid;
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const float h = ph.smoothing;
    const float eps = 0.01f * h * h;
    const float viscFluid = 2.0f * ph.alpha * ph.soundSpeed * h;
    const float* position = reinterpret_cast<const float*>(f.position);  // Vec4: x y z w
    const float* velocity = reinterpret_cast<const float*>(f.velocity);
    const uint32_t* slots = stage.list.index + static_cast<size_t>(i) * static_cast<size_t>(capacity);
    const Lanes zero = Splat(0.0f);
    Lanes ax = zero, ay = zero, az = zero, pSum = zero, wSum = zero;
    for (uint32_t base = 0; base < found; base += kLanes) {
      LaneInts index;
      for (int l = 0; l < kLanes; ++l) {
        // Lanes past the list read particle i itself: r2 = 0, which the pair test excludes.
        index[l] = static_cast<int32_t>(base + static_cast<uint32_t>(l) < found ? slots[base + l] : static_cast<uint32_t>(i));
      }
      Lanes xj, yj, zj;
      GatherXyz(position, index, &xj, &yj, &zj);
      const Lanes dx = P.xi.x - xj, dy = P.xi.y - yj, dz = P.xi.z - zj;
      const Lanes r2 = dx * dx + dy * dy + dz * dz;
      const LaneInts pair = And(Less(r2, Splat(k.H2)), NotEq(r2, zero));
      if (Bits(pair) == 0) continue;
      const Lanes rhoj = Gather(f.density, index);
      const Lanes r = Sqrt(r2);
      const Lanes q = r * k.invH;
      const Lanes grad = GradFactorLanes(k, q, r, pair);
      if (P.shepard) {  // CubicSpline::W / rho_j
        const Lanes wj = KernelWLanes(k, q, pair) / rhoj;
        pSum += Gather(f.pressure, index) * wj;
        wSum += wj;
      }
      Lanes term = P.pTermI + Gather(f.pressureTerm, index);
      Lanes ux, uy, uz;
      GatherXyz(velocity, index, &ux, &uy, &uz);
      const Lanes vx = (P.vi.x - ux) * dx + (P.vi.y - uy) * dy + (P.vi.z - uz) * dz;
      term = Select(Less(vx, zero), term - viscFluid * vx / ((r2 + eps) * (P.rhoi + rhoj)), term);
      const Lanes s = ph.mass * term * grad;
      ax -= dx * s;
      ay -= dy * s;
      az -= dz * s;
    }
    if (P.shepard) {
      P.pAverage += SumLanes(pSum);
      P.weight += SumLanes(wSum);
    }
    if (P.nearWall) Walls(P, &ax, &ay, &az);
    stage.Store(i, P, Vec3{SumLanes(ax), SumLanes(ay), SumLanes(az)});
  }

  /// ForceStage::End's wall terms, added into the lanes: the wall particles of i's cells (its own
  /// ForEachInCells scan) collected kLanes at a time.
  void Walls(const ForceParticle& P, Lanes* ax, Lanes* ay, Lanes* az) const {
    const GridView& g = stage.grid;
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const float eps = 0.01f * ph.smoothing * ph.smoothing;
    const ForceStage::WallTerms w = stage.Walls(P);
    const float* boundary = reinterpret_cast<const float*>(g.boundary);  // Vec4: x y z Psi
    const Lanes zero = Splat(0.0f);
    Lanes laneNumber;
    for (int l = 0; l < kLanes; ++l) laneNumber[l] = static_cast<float>(l);
    LaneInts index;
    int n = 0;
    auto flush = [&]() {
      for (int l = n; l < kLanes; ++l) index[l] = index[0];  // padding, masked off below
      Lanes xb, yb, zb, psi;
      GatherXyzw(boundary, index, &xb, &yb, &zb, &psi);
      const Lanes dx = P.xi.x - xb, dy = P.xi.y - yb, dz = P.xi.z - zb;
      const Lanes r2 = dx * dx + dy * dy + dz * dz;
      const LaneInts pair = And(And(Less(r2, Splat(k.H2)), NotEq(r2, zero)),
                                    Less(laneNumber, Splat(static_cast<float>(n))));
      n = 0;
      if (Bits(pair) == 0) return;
      const Lanes r = Sqrt(r2);
      const Lanes grad = GradFactorLanes(k, r * k.invH, r, pair);
      Lanes term = ph.wallDensity ? ph.boundaryGradScale * (P.pTermI + Gather(g.boundaryPressureTerm, index))
                                    : Splat(w.pressureTerm);
      const Lanes vx = P.vi.x * dx + P.vi.y * dy + P.vi.z * dz;  // static walls: v_b = 0
      term = Select(Less(vx, zero), term - Gather(g.boundaryAlpha, index) * w.viscosity * vx / (r2 + eps), term);
      const Lanes s = psi * term * grad;
      *ax -= dx * s;
      *ay -= dy * s;
      *az -= dz * s;
    };
    ForEachInCells(g, g.boundaryStart, g.boundaryEnd, g.boundary, P.xi, [&](uint32_t j, Vec3) {
      index[n++] = static_cast<int32_t>(j);
      if (n == kLanes) flush();
    });
    if (n > 0) flush();
  }
};

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

#undef SPHXR_LANE_BYTES

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
