#pragma once
// The SIMD forms of DFSPH's three neighbour passes (solvers/dfsph/dfsph_stages.h): the factor, and the two
// passes of each Jacobi iteration (Predict: D rho^_i/Dt; Correct: the velocity update), per particle over
// its neighbour list kLanes neighbours at a time, and the factor's wall particles kLanes at a time (as
// the PBF passes, solvers/pbf/pbf_simd.h). The physics is the scalar stages'; the sums' order differs (rounding
// only), a list that overflowed falls back to the scalar stage (a scan of the cells, no cache), and the
// paddles' particles (a few near any fluid particle) stay scalar. CpuLauncher::ForEach runs these in place
// of the scalar stages (SimdForm); the CUDA backend and cpu-reference run the scalar ones.
//
// The pair cache (DfsphView::pairGrad): the factor pass keeps each listed pair's G_ij = V grad W_ij
// lane-blocked (kLanes x, then kLanes y, then kLanes z; zero in the lanes past the list's end), in place
// of the scalar stages' one Vec3 a slot, so that an iteration's passes load three vectors a batch and
// gather only the neighbours' velocity or increment. Deterministic for any thread count: a particle's
// sums never depend on the schedule.
#include <cstdint>

#include "cpu/lists.h"
#include "cpu/simd.h"
#include "solvers/dfsph/dfsph_stages.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

struct DfsphFactorListStage {
  DfsphFactorStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(stage.fluid.position[i]);
    float* cache = PairCacheRow(stage.view.pairGrad, stage.view.pairStride, i);
    const Lanes zero = Splat(0.0f);
    Lanes gx = zero, gy = zero, gz = zero, s2 = zero;
    // Every batch is stored (zeros where no pair is), so that the iterations read whole batches.
    ForListLanes(
        stage.list, stage.fluid, k, i, xi,
        [&](LaneInts, Lanes dx, Lanes dy, Lanes dz, Lanes r, Lanes q, LaneInts pair, int batch) {
          const Lanes grad = ph.volume * GradFactorLanes(k, q, r, pair);
          const Lanes ax = dx * grad, ay = dy * grad, az = dz * grad;
          gx += ax, gy += ay, gz += az;
          s2 += ax * ax + ay * ay + az * az;
          StorePairBatch(cache, batch, ax, ay, az);
        },
        /*everyBatch=*/true);
    Lanes bx = zero, by = zero, bz = zero;
    int32_t walls = 0;
    if (stage.fluid.position[i].w != 0.0f) {  // a wall or a paddle within the support (DensityStage's flag)
      const float invRho0 = ph.invRestDensity;
      ForWallLanes(stage.grid, k, xi, [&](Lanes dx, Lanes dy, Lanes dz, Lanes r, Lanes q, Lanes psi, LaneInts pair) {
        const Lanes grad = psi * invRho0 * GradFactorLanes(k, q, r, pair);
        bx += dx * grad, by += dy * grad, bz += dz * grad;
        walls += __builtin_popcount(Bits(pair));
      });
    }
    stage.Store(i, xi, Vec3{SumLanes(gx), SumLanes(gy), SumLanes(gz)}, SumLanes(s2),
                Vec3{SumLanes(bx), SumLanes(by), SumLanes(bz)}, static_cast<int32_t>(stage.list.count[i]) + walls);
  }
};

struct DfsphPredictListStage {
  DfsphPredictStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    // D rho^_i / Dt = sum_j (v_i - v_j) . G_ij over the cache (the padding lanes' G is 0), plus the walls'
    const DfsphView& view = stage.view;
    const float* velocity = reinterpret_cast<const float*>(stage.fluid.velocity);
    const Vec3 vi = Xyz(stage.fluid.velocity[i]);
    Lanes rate = Splat(0.0f);
    ForCachedPairs(stage.list, PairCacheRow(view.pairGrad, view.pairStride, i), i,
                   [&](LaneInts index, Lanes gx, Lanes gy, Lanes gz) {
                     Lanes vx, vy, vz;
                     GatherXyz(velocity, index, &vx, &vy, &vz);
                     rate += (vi.x - vx) * gx + (vi.y - vy) * gy + (vi.z - vz) * gz;
                   });
    const Vec4 b = view.boundary[i];
    stage.Store(i, SumLanes(rate) + Dot(vi, Xyz(b)) - b.w);
  }
};

struct DfsphCorrectListStage {
  DfsphCorrectStage stage;

  void operator()(int i) const {
    if (Overflowed(stage.list, i)) {
      stage(i);
      return;
    }
    // sum_j (delta_i + delta_j) G_ij over the cache, plus the walls' 2 delta_i gB_i
    const DfsphView& view = stage.view;
    const float di = view.delta[i];
    const Lanes zero = Splat(0.0f);
    Lanes cx = zero, cy = zero, cz = zero;
    ForCachedPairs(stage.list, PairCacheRow(view.pairGrad, view.pairStride, i), i,
                   [&](LaneInts index, Lanes gx, Lanes gy, Lanes gz) {
                     const Lanes s = di + Gather(view.delta, index);
                     cx += s * gx, cy += s * gy, cz += s * gz;
                   });
    stage.Store(i, Vec3{SumLanes(cx), SumLanes(cy), SumLanes(cz)} + Xyz(view.boundary[i]) * (2.0f * di));
  }
};

template <>
struct SimdForm<DfsphFactorStage> {
  using type = DfsphFactorListStage;
};
template <>
struct SimdForm<DfsphPredictStage> {
  using type = DfsphPredictListStage;
};
template <>
struct SimdForm<DfsphCorrectStage> {
  using type = DfsphCorrectListStage;
};

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
