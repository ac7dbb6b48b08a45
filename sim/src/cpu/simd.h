#pragma once
// The CPU stages' vector values (GCC/Clang vector extensions, kLanes floats) and their few operations
// that need intrinsics: square root, compare, select, gathers, and the kernel in every lane.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#if defined(__AVX512F__) || defined(__AVX__) || defined(__SSE2__)
#include <immintrin.h>
#endif

#include "kernel.h"
#include "sphxr/common/hd.h"

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
/// 32-bit result, then a 128-bit reload that the store buffer cannot forward; with 16 lanes in two
/// halves that makes the density and force stages 2-3x slower), so that tier
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

/// SimdForm<Stage>::type: the SIMD form CpuLauncher::ForEach runs in place of a scalar stage (where
/// one is declared, beside the form: solvers/pbf/pbf_simd.h).
template <class Stage>
struct SimdForm {};

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

/// CubicSpline::GradFactor in every lane from q = r / H and r (0 where `pair` is off or q >= 1; r > 0
/// where it is used).
inline Lanes GradFactorLanes(const CubicSpline& k, Lanes q, Lanes r, LaneInts pair) {
  const Lanes t = 1.0f - q;
  return Select(And(pair, Less(q, Splat(1.0f))),
                  Select(LessEq(q, Splat(0.5f)), k.gradA * (3.0f * q - 2.0f), -k.gradB * t * t / r), Splat(0.0f));
}

#undef SPHXR_LANE_BYTES

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
