#pragma once
// The SIMD forms of position-based fluids' three neighbour passes (solvers/pbf_stages.h): the lambda
// pass, the correction pass and XSPH, per particle over its neighbour list kLanes neighbours at a time
// (as ForceListStage), and the wall particles of its cells kLanes at a time. The physics is the scalar
// stage's; the sums' order differs (rounding only), a list that overflowed falls back to the scalar
// stage, and the paddles' particles (a few near any fluid particle) stay scalar. CpuLauncher::ForEach
// runs these in place of the scalar stages (SimdForm); the CUDA backend and cpu-reference run the scalar
// ones. Deterministic for any thread count: a particle's sums never depend on the schedule.
//
// The pair cache (PbfView::pairGrad): between an iteration's lambda pass and its correction pass no
// particle moves, so the lambda pass keeps each listed pair's V grad W_ij (kLanes pairs of x, then y,
// then z) and each particle's own terms, lambda_i (sum_j V grad W_ij + B_i) + sum_j s_corr V grad W_ij.
// The correction pass is then sum_j lambda_j V grad W_ij over the cache plus the own terms: a gather of
// lambda and three loads a batch, no position, square root or kernel. It took the correction pass
// from as long as the lambda pass to a fifth of it on `stir` (docs/design/pbf.md).
#include <cstdint>
#include <cstring>

#include "cpu/simd.h"
#include "solvers/pbf_stages.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

/// The lanes of particle i's list: up to kLanes entries from `base`, lanes past the end set to i itself
/// (masked off by the pair test, which excludes j == i as ForEachOther does).
SPHXR_INLINE LaneInts ListLanes(const uint32_t* slots, uint32_t base, uint32_t found, int i) {
  LaneInts index;
  for (int l = 0; l < kLanes; ++l) {
    index[l] = static_cast<int32_t>(base + static_cast<uint32_t>(l) < found ? slots[base + l] : static_cast<uint32_t>(i));
  }
  return index;
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

/// kLanes floats from p (any alignment), and back.
SPHXR_INLINE Lanes LoadLanes(const float* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
SPHXR_INLINE void StoreLanes(float* p, Lanes v) { std::memcpy(p, &v, sizeof v); }

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

/// PbfCorr (MM13's s_corr) in every lane from the pairs' W_ij.
SPHXR_INLINE Lanes CorrLanes(const Physics& ph, Lanes w) {
  if (ph.pbfCorrK <= 0.0f) return Splat(0.0f);
  const Lanes wq = w * ph.pbfInvCorrW;
  Lanes p = wq;
  for (int e = 1; e < ph.pbfCorrN; ++e) p *= wq;
  return -ph.pbfCorrK * p;
}

struct PbfLambdaListStage {
  PbfLambdaStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(stage.fluid.position[i]);
    const PbfView& view = stage.view;
    // Each batch's V grad W_ij kept in the pair cache (every batch, so that the correction pass reads
    // zeros where no pair is), and the sum of the pairs' s_corr V grad W_ij.
    SPHXR_ASSERT(view.pairGrad && view.ownCorrection);  // the CPU launcher's kPbfPairCache
    float* cache = view.pairGrad + static_cast<size_t>(i) * static_cast<size_t>(view.pairStride);
    const bool corrected = ph.pbfCorrK > 0.0f;
    const Lanes zero = Splat(0.0f);
    Lanes w = zero, s2 = zero, gx = zero, gy = zero, gz = zero, sx = zero, sy = zero, sz = zero;
    ForListLanes(
        stage.list, stage.fluid, k, i, xi,
        [&](LaneInts, Lanes dx, Lanes dy, Lanes dz, Lanes r, Lanes q, LaneInts pair, int batch) {
          const Lanes wj = KernelWLanes(k, q, pair);
          w += wj;
          const Lanes grad = ph.volume * GradFactorLanes(k, q, r, pair);
          const Lanes ax = dx * grad, ay = dy * grad, az = dz * grad;
          gx += ax, gy += ay, gz += az;
          s2 += ax * ax + ay * ay + az * az;
          float* out = cache + 3 * kLanes * batch;
          StoreLanes(out, ax);
          StoreLanes(out + kLanes, ay);
          StoreLanes(out + 2 * kLanes, az);
          if (corrected) {
            const Lanes corr = CorrLanes(ph, wj);
            sx += corr * ax, sy += corr * ay, sz += corr * az;
          }
        },
        /*everyBatch=*/true);
    const Vec3 gradF{SumLanes(gx), SumLanes(gy), SumLanes(gz)};
    const float sumW = k.W(0.0f) + SumLanes(w);
    const float sum2 = SumLanes(s2);
    const float invRho0 = ph.invRestDensity;
    const GridView& g = stage.grid;
    Lanes bw = zero, bx = zero, by = zero, bz = zero;
    ForWallLanes(g, k, xi, [&](Lanes dx, Lanes dy, Lanes dz, Lanes r, Lanes q, Lanes psi, LaneInts pair) {
      bw += psi * KernelWLanes(k, q, pair);
      const Lanes grad = psi * invRho0 * GradFactorLanes(k, q, r, pair);
      bx += dx * grad, by += dy * grad, bz += dz * grad;
    });
    float sumBoundary = SumLanes(bw);
    Vec3 gradB{SumLanes(bx), SumLanes(by), SumLanes(bz)};
    ForEachBodyNear(g, xi, k.H2, [&](float psi, Vec3 d) {
      const float r = sqrtf(Dot(d, d));
      sumBoundary += psi * k.W(r);
      gradB += d * (psi * invRho0 * k.GradFactor(r));
    });
    view.boundaryGrad[i] = MakeVec4(gradB);
    const Vec3 gradI = gradF + gradB;
    const float li = stage.Finish(i, ph.mass * sumW + sumBoundary, sum2 + Dot(gradI, gradI));
    // The correction's terms that the pass below need not visit the pairs for: lambda_i's and s_corr's.
    view.ownCorrection[i] = MakeVec4(gradI * li + Vec3{SumLanes(sx), SumLanes(sy), SumLanes(sz)});
  }
};

struct PbfCorrectListStage {
  PbfCorrectStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    // sum_j lambda_j V grad W_ij over the lambda pass's pair cache, plus the particle's own terms
    const PbfView& view = stage.view;
    SPHXR_ASSERT(view.pairGrad && view.ownCorrection);
    const uint32_t found = stage.list.count[i];
    const uint32_t* slots = stage.list.index + static_cast<size_t>(i) * static_cast<size_t>(stage.list.maxNeighbours);
    const float* cache = view.pairGrad + static_cast<size_t>(i) * static_cast<size_t>(view.pairStride);
    const Lanes zero = Splat(0.0f);
    Lanes cx = zero, cy = zero, cz = zero;
    for (uint32_t base = 0; base < found; base += kLanes, cache += 3 * kLanes) {
      const Lanes lj = Gather(view.lambda, ListLanes(slots, base, found, i));  // padding: i, whose term is 0
      cx += lj * LoadLanes(cache), cy += lj * LoadLanes(cache + kLanes), cz += lj * LoadLanes(cache + 2 * kLanes);
    }
    view.delta[i] = MakeVec4(Vec3{SumLanes(cx), SumLanes(cy), SumLanes(cz)} + Xyz(view.ownCorrection[i]));
  }
};

struct PbfXsphListStage {
  PbfXsphStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const FluidView& f = stage.fluid;
    const Vec3 xi = Xyz(f.position[i]);
    const Vec3 vi = Xyz(f.velocity[i]);
    const float* velocity = reinterpret_cast<const float*>(f.velocity);
    const Lanes zero = Splat(0.0f);
    Lanes ux = zero, uy = zero, uz = zero;
    ForListLanes(stage.list, f, k, i, xi, [&](LaneInts index, Lanes, Lanes, Lanes, Lanes, Lanes q, LaneInts pair, int) {
      const Lanes wj = KernelWLanes(k, q, pair);
      Lanes vx, vy, vz;
      GatherXyz(velocity, index, &vx, &vy, &vz);
      ux += (vx - vi.x) * wj, uy += (vy - vi.y) * wj, uz += (vz - vi.z) * wj;
    });
    const Vec3 dv{SumLanes(ux), SumLanes(uy), SumLanes(uz)};
    stage.view.delta[i] = MakeVec4(dv * (ph.pbfXsph * ph.volume));
  }
};

template <>
struct SimdForm<PbfLambdaStage> {
  using type = PbfLambdaListStage;
};
template <>
struct SimdForm<PbfCorrectStage> {
  using type = PbfCorrectListStage;
};
template <>
struct SimdForm<PbfXsphStage> {
  using type = PbfXsphListStage;
};

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
