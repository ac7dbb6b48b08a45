#pragma once
// The SIMD forms of position-based fluids' three neighbour passes (solvers/pbf_stages.h): the lambda
// pass, the correction pass and XSPH, per particle over its neighbour list kLanes neighbours at a time
// (as ForceListStage), and the wall particles of its cells kLanes at a time. The physics is the scalar
// stage's; the sums' order differs (rounding only), a list that overflowed falls back to the scalar
// stage, and the paddles' particles (a few near any fluid particle) stay scalar. CpuLauncher::ForEach
// runs these in place of the scalar stages (SimdForm); the CUDA backend and cpu-reference run the scalar
// ones. Deterministic for any thread count: a particle's sums never depend on the schedule.
#include <cstdint>

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

/// f(index, count) for the wall particles of xi's cells, kLanes at a time (count <= kLanes valid lanes;
/// the rest repeat lane 0), where the cell is near a wall (the scalar ForEachBoundaryNear's test).
template <class F>
SPHXR_INLINE void ForWallLanes(const GridView& g, Vec3 xi, F&& f) {
  int cx, cy, cz;
  g.CellOf(xi, &cx, &cy, &cz);
  if (!g.boundaryNear[g.Linear(cx, cy, cz)]) return;
  LaneInts index;
  int n = 0;
  ForEachInCells(g, g.boundaryStart, g.boundaryEnd, g.boundary, xi, [&](uint32_t b, Vec3) {
    index[n++] = static_cast<int32_t>(b);
    if (n == kLanes) {
      f(index, n);
      n = 0;
    }
  });
  if (n > 0) {
    for (int l = n; l < kLanes; ++l) index[l] = index[0];
    f(index, n);
  }
}

/// The lanes l < n as a mask.
SPHXR_INLINE LaneInts FirstLanes(int n) {
  Lanes laneNumber;
  for (int l = 0; l < kLanes; ++l) laneNumber[l] = static_cast<float>(l);
  return Less(laneNumber, Splat(static_cast<float>(n)));
}

struct PbfLambdaListStage {
  PbfLambdaStage stage;

  void operator()(int i) const {
    const NeighbourList& list = stage.list;
    const uint32_t found = list.count[i];
    const uint32_t capacity = static_cast<uint32_t>(list.maxNeighbours);
    if (found > capacity) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const FluidView& f = stage.fluid;
    const Vec3 xi = Xyz(f.position[i]);
    const float* position = reinterpret_cast<const float*>(f.position);
    const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(capacity);
    const Lanes zero = Splat(0.0f);
    const LaneInts self = LaneInts{} + i;
    Lanes w = zero, s2 = zero, gx = zero, gy = zero, gz = zero;
    for (uint32_t base = 0; base < found; base += kLanes) {
      const LaneInts index = ListLanes(slots, base, found, i);
      Lanes xj, yj, zj;
      GatherXyz(position, index, &xj, &yj, &zj);
      const Lanes dx = xi.x - xj, dy = xi.y - yj, dz = xi.z - zj;
      const Lanes r2 = dx * dx + dy * dy + dz * dz;
      const LaneInts pair = And(Less(r2, Splat(k.H2)), index != self);
      if (Bits(pair) == 0) continue;
      const Lanes r = Sqrt(r2);
      const Lanes q = r * k.invH;
      w += KernelWLanes(k, q, pair);
      const Lanes grad = ph.volume * GradFactorLanes(k, q, r, pair);
      const Lanes ax = dx * grad, ay = dy * grad, az = dz * grad;
      gx += ax, gy += ay, gz += az;
      s2 += ax * ax + ay * ay + az * az;
    }
    Vec3 gradI{SumLanes(gx), SumLanes(gy), SumLanes(gz)};
    const float sumW = k.W(0.0f) + SumLanes(w);
    const float sum2 = SumLanes(s2);
    const float invRho0 = ph.invRestDensity;
    const GridView& g = stage.grid;
    const float* boundary = reinterpret_cast<const float*>(g.boundary);  // Vec4: x y z Psi
    Lanes bw = zero, bx = zero, by = zero, bz = zero;
    ForWallLanes(g, xi, [&](LaneInts index, int n) {
      Lanes xb, yb, zb, psi;
      GatherXyzw(boundary, index, &xb, &yb, &zb, &psi);
      const Lanes dx = xi.x - xb, dy = xi.y - yb, dz = xi.z - zb;
      const Lanes r2 = dx * dx + dy * dy + dz * dz;
      const LaneInts pair = And(Less(r2, Splat(k.H2)), FirstLanes(n));
      if (Bits(pair) == 0) return;
      const Lanes r = Sqrt(r2);
      const Lanes q = r * k.invH;
      bw += psi * KernelWLanes(k, q, pair);
      const Lanes grad = psi * invRho0 * GradFactorLanes(k, q, r, pair);
      bx += dx * grad, by += dy * grad, bz += dz * grad;
    });
    float sumBoundary = SumLanes(bw);
    gradI += Vec3{SumLanes(bx), SumLanes(by), SumLanes(bz)};
    if (g.MovingNear(xi)) {
      ForEachInCells(g, g.bodyStart, g.bodyEnd, g.body, xi, [&](uint32_t b, Vec3 d) {
        const float r2 = Dot(d, d);
        if (r2 >= k.H2) return;
        const float r = sqrtf(r2);
        const float psi = g.body[b].w;
        sumBoundary += psi * k.W(r);
        gradI += d * (psi * invRho0 * k.GradFactor(r));
      });
    }
    stage.Finish(i, ph.mass * sumW + sumBoundary, sum2 + Dot(gradI, gradI));
  }
};

struct PbfCorrectListStage {
  PbfCorrectStage stage;

  void operator()(int i) const {
    const NeighbourList& list = stage.list;
    const uint32_t found = list.count[i];
    const uint32_t capacity = static_cast<uint32_t>(list.maxNeighbours);
    if (found > capacity) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const FluidView& f = stage.fluid;
    const Vec3 xi = Xyz(f.position[i]);
    const float li = stage.view.lambda[i];
    const float* position = reinterpret_cast<const float*>(f.position);
    const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(capacity);
    const Lanes zero = Splat(0.0f);
    const LaneInts self = LaneInts{} + i;
    Lanes cx = zero, cy = zero, cz = zero;
    for (uint32_t base = 0; base < found; base += kLanes) {
      const LaneInts index = ListLanes(slots, base, found, i);
      Lanes xj, yj, zj;
      GatherXyz(position, index, &xj, &yj, &zj);
      const Lanes dx = xi.x - xj, dy = xi.y - yj, dz = xi.z - zj;
      const Lanes r2 = dx * dx + dy * dy + dz * dz;
      const LaneInts pair = And(Less(r2, Splat(k.H2)), index != self);
      if (Bits(pair) == 0) continue;
      const Lanes r = Sqrt(r2);
      const Lanes q = r * k.invH;
      Lanes corr = zero;
      if (ph.pbfCorrK > 0.0f) {
        const Lanes wq = KernelWLanes(k, q, pair) * ph.pbfInvCorrW;
        Lanes p = wq;
        for (int e = 1; e < ph.pbfCorrN; ++e) p *= wq;
        corr = -ph.pbfCorrK * p;
      }
      const Lanes s = (li + Gather(stage.view.lambda, index) + corr) * ph.volume * GradFactorLanes(k, q, r, pair);
      cx += dx * s, cy += dy * s, cz += dz * s;
    }
    Vec3 dx{SumLanes(cx), SumLanes(cy), SumLanes(cz)};
    if (li != 0.0f) {  // the walls' and paddles' terms are li times theirs
      const float scale = li * ph.invRestDensity;
      const GridView& g = stage.grid;
      const float* boundary = reinterpret_cast<const float*>(g.boundary);
      Lanes bx = zero, by = zero, bz = zero;
      ForWallLanes(g, xi, [&](LaneInts index, int n) {
        Lanes xb, yb, zb, psi;
        GatherXyzw(boundary, index, &xb, &yb, &zb, &psi);
        const Lanes ex = xi.x - xb, ey = xi.y - yb, ez = xi.z - zb;
        const Lanes r2 = ex * ex + ey * ey + ez * ez;
        const LaneInts pair = And(Less(r2, Splat(k.H2)), FirstLanes(n));
        if (Bits(pair) == 0) return;
        const Lanes r = Sqrt(r2);
        const Lanes s = scale * psi * GradFactorLanes(k, r * k.invH, r, pair);
        bx += ex * s, by += ey * s, bz += ez * s;
      });
      dx += Vec3{SumLanes(bx), SumLanes(by), SumLanes(bz)};
      if (g.MovingNear(xi)) {
        ForEachInCells(g, g.bodyStart, g.bodyEnd, g.body, xi, [&](uint32_t b, Vec3 d) {
          const float r2 = Dot(d, d);
          if (r2 < k.H2) dx += d * (scale * g.body[b].w * k.GradFactor(sqrtf(r2)));
        });
      }
    }
    stage.view.delta[i] = MakeVec4(dx);
  }
};

struct PbfXsphListStage {
  PbfXsphStage stage;

  void operator()(int i) const {
    const NeighbourList& list = stage.list;
    const uint32_t found = list.count[i];
    const uint32_t capacity = static_cast<uint32_t>(list.maxNeighbours);
    if (found > capacity) {
      stage(i);
      return;
    }
    const Physics& ph = stage.ph;
    const CubicSpline k = ph.kernel;
    const FluidView& f = stage.fluid;
    const Vec3 xi = Xyz(f.position[i]);
    const Vec3 vi = Xyz(f.velocity[i]);
    const float* position = reinterpret_cast<const float*>(f.position);
    const float* velocity = reinterpret_cast<const float*>(f.velocity);
    const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(capacity);
    const Lanes zero = Splat(0.0f);
    const LaneInts self = LaneInts{} + i;
    Lanes ux = zero, uy = zero, uz = zero;
    for (uint32_t base = 0; base < found; base += kLanes) {
      const LaneInts index = ListLanes(slots, base, found, i);
      Lanes xj, yj, zj;
      GatherXyz(position, index, &xj, &yj, &zj);
      const Lanes dx = xi.x - xj, dy = xi.y - yj, dz = xi.z - zj;
      const Lanes r2 = dx * dx + dy * dy + dz * dz;
      const LaneInts pair = And(Less(r2, Splat(k.H2)), index != self);
      if (Bits(pair) == 0) continue;
      const Lanes wj = KernelWLanes(k, Sqrt(r2) * k.invH, pair);
      Lanes vx, vy, vz;
      GatherXyz(velocity, index, &vx, &vy, &vz);
      ux += (vx - vi.x) * wj, uy += (vy - vi.y) * wj, uz += (vz - vi.z) * wj;
    }
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
