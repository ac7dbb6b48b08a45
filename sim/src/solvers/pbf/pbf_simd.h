#pragma once
// The SIMD forms of position-based fluids' three neighbour passes (solvers/pbf/pbf_stages.h): the lambda
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

#include "cpu/lists.h"
#include "cpu/simd.h"
#include "solvers/pbf/pbf_stages.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

/// PbfCorr (MM13's s_corr) in every lane from the pairs' W_ij.
SPHXR_INLINE Lanes CorrLanes(const PbfConstants& pbf, Lanes w) {
  if (pbf.corrK <= 0.0f) return Splat(0.0f);
  const Lanes wq = w * pbf.invCorrW;
  Lanes p = wq;
  for (int e = 1; e < pbf.corrN; ++e) p *= wq;
  return -pbf.corrK * p;
}

struct PbfLambdaListStage {
  PbfLambdaStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const PbfConstants& pbf = stage.pbf;
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(stage.fluid.position[i]);
    const PbfView& view = stage.view;
    // Each batch's V grad W_ij kept in the pair cache (every batch, so that the correction pass reads
    // zeros where no pair is), and the sum of the pairs' s_corr V grad W_ij.
    SPHXR_ASSERT(view.pairGrad && view.ownCorrection);  // the CPU launcher's kPairCache
    float* cache = PairCacheRow(view.pairGrad, view.pairStride, i);
    const bool corrected = pbf.corrK > 0.0f;
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
          StorePairBatch(cache, batch, ax, ay, az);
          if (corrected) {
            const Lanes corr = CorrLanes(pbf, wj);
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
    const Lanes zero = Splat(0.0f);
    Lanes cx = zero, cy = zero, cz = zero;
    ForCachedPairs(stage.list, PairCacheRow(view.pairGrad, view.pairStride, i), i,
                   [&](LaneInts index, Lanes gx, Lanes gy, Lanes gz) {
                     const Lanes lj = Gather(view.lambda, index);  // padding: i, whose term is 0
                     cx += lj * gx, cy += lj * gy, cz += lj * gz;
                   });
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
    const PbfConstants& pbf = stage.pbf;
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
    stage.view.delta[i] = MakeVec4(dv * (pbf.xsph * ph.volume));
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
