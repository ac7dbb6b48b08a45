#pragma once
// ForceStage (stages/forces.h) over each particle's neighbour list, kLanes neighbours at a time.
#include <cstdint>

#include "cpu/blocks.h"
#include "cpu/lists.h"
#include "cpu/simd.h"
#include "stages/forces.h"

namespace sphxr::sim {
inline namespace SPHXR_CPU_TIER {

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
      // Lanes past the list read particle i itself: r2 = 0, which the pair test excludes.
      const LaneInts index = ListLanes(slots, base, found, i);
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

}  // namespace SPHXR_CPU_TIER
}  // namespace sphxr::sim
