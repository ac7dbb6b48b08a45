#pragma once
// Stage 5 of a step: a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) gradW_ij (Becker & Teschner 2007,
// eq. 6 and 10), the walls' and moving bodies' terms (Akinci et al. 2012, eq. 10-11, in the symmetric
// form) and gravity. The CPU's SIMD form is cpu/forces.h.
#include <cstdint>

#include "stages/views.h"

namespace sphxr::sim {

/// Sum over the moving boundary particles b near xi of Psi_b (s_b pairTerm + Pi_ib) gradW_ib, with the
/// relative velocity v_i - v_b in the viscosity (Akinci et al. 2012, eq. 10-11 as for the walls).
SPHXR_HD SPHXR_INLINE Vec3 BodyAcceleration(const GridView& grid, const Physics& ph, Vec3 xi, Vec3 vi, float rhoi,
                                            float pairTerm, const uint32_t* start, const uint32_t* end) {
  const CubicSpline k = ph.kernel;
  const float h = ph.smoothing;
  const float eps = 0.01f * h * h;
  const float viscWall = ph.soundSpeed * h / (2.0f * rhoi);
  const float pressure = ph.bodyGradScale * pairTerm;
  Vec3 sum{0.0f, 0.0f, 0.0f};
  ForEachInCells(grid, start, end, grid.body, xi, [&](uint32_t j, Vec3 d) {
    const float r2 = Dot(d, d);
    if (r2 >= k.H2 || r2 == 0.0f) return;
    const Vec4 vb = grid.bodyVelocity[j];
    float term = pressure;
    const float vx = Dot(vi - Xyz(vb), d);
    if (vx < 0.0f) term -= vb.w * viscWall * vx / (r2 + eps);
    sum += d * (grid.body[j].w * term * k.GradFactor(sqrtf(r2)));
  });
  return sum;
}

// ---- stage 5: pressure, viscosity and gravity ----------------------------------------------------
/// What the force stage knows of particle i before its neighbours (ForceStage::Begin).
struct ForceParticle {
  Vec3 xi, vi;
  float rhoi, pI, pTermI;  // density, pressure, p_i / rho_i^2
  bool nearWall;  // a wall within the support (the density stage's flag)
  bool shepard;   // the Shepard pressure average is needed (mirrored walls or a moving body near)
  float pAverage, weight;  // Shepard sums, self included
};

/// One work item per particle (both backends). The CPU backend runs the same Begin and End around a
/// SIMD sum over the neighbour list (ForceListStage, cpu/forces.h).
struct ForceStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  float* bodyPressureTerm = nullptr;  // per particle near a moving body: p_i/rho_i^2 + p_b/rho_i^2 (for its reaction)
  SPHXR_HD void operator()(int i) const {
    ForceParticle P = Begin(i);
    const Vec3 xi = P.xi, vi = P.vi;
    const float rhoi = P.rhoi, pTermI = P.pTermI;
    const CubicSpline k = ph.kernel;
    const float h = ph.smoothing;
    const float eps = 0.01f * h * h;
    const float viscFluid = 2.0f * ph.alpha * ph.soundSpeed * h;
    Vec3 a{0.0f, 0.0f, 0.0f};
    auto fluidNeighbour = [&](uint32_t j, Vec3 d) {
      const float r2 = Dot(d, d);
      if (r2 >= k.H2 || r2 == 0.0f) return;  // r2 == 0: self, or a coincident particle (no direction)
      const float rhoj = fluid.density[j];
      const float r = sqrtf(r2);
      if (P.shepard) {
        const float wj = k.W(r) / rhoj;
        P.pAverage += fluid.pressure[j] * wj;
        P.weight += wj;
      }
      float term = pTermI + fluid.pressureTerm[j];
      const Vec3 vij = vi - Xyz(fluid.velocity[j]);
      const float vx = Dot(vij, d);
      if (vx < 0.0f) term -= viscFluid * vx / ((r2 + eps) * (rhoi + rhoj));
      a -= d * (ph.mass * term * k.GradFactor(r));
    };
    ForEachFluidNeighbour(grid, fluid, list, i, xi, fluidNeighbour);
    End(i, P, a);
  }

  SPHXR_HD SPHXR_INLINE ForceParticle Begin(int i) const {
    SPHXR_ASSERT(i >= 0 && i < fluid.count);
    ForceParticle P;
    P.xi = Xyz(fluid.position[i]);
    P.vi = Xyz(fluid.velocity[i]);
    P.rhoi = fluid.density[i];
    P.pI = fluid.pressure[i];
    P.pTermI = fluid.pressureTerm[i];
    P.nearWall = fluid.position[i].w != 0.0f;
    // The Shepard average feeds the mirrored wall pressure (and the bodies', which are always mirrored).
    P.shepard = P.nearWall && (!ph.wallDensity || grid.MovingNear(P.xi));
    P.pAverage = P.pI * ph.kernel.W(0.0f) / P.rhoi;
    P.weight = ph.kernel.W(0.0f) / P.rhoi;
    return P;
  }

  /// The constants of particle i's wall pair terms (ForceStage::End, and the CPU's SIMD wall sum).
  struct WallTerms {
    float pWall;          // mirrored p_b
    float pressureTerm;   // mirrored walls: s (p_i/rho_i^2 + p_b/rho_i^2), the same for every wall particle
    float viscosity;      // c h / (2 rho_i), times alpha_b (v_i . x_ib) / (r^2 + eps) in Pi_ib
  };
  SPHXR_HD SPHXR_INLINE WallTerms Walls(const ForceParticle& P) const {
    // Wall pressure. Mirrored (the default): p_b = p_i (Akinci et al. 2012), but never below the average
    // pressure of i's fluid neighbours (the extrapolation of Adami et al. 2012, taken at i). Near the free
    // surface p_i is clamped to 0 while the particles below it push it with their own p_j > 0; mirroring
    // alone then gives the wall no strength and the particle sinks into it. Wall density (tank
    // "wall_pressure": "wall_density"): p_b/rho_b^2 of each wall particle from WallPressureStage.
    // Moving bodies always use the mirrored pressure.
    WallTerms w;
    w.pWall = AtLeast(P.pAverage / P.weight, P.pI);  // fmaxf is a library call on the host (perf: 0.6 % of a step)
    w.pressureTerm = ph.boundaryGradScale * (P.pTermI + w.pWall / (P.rhoi * P.rhoi));
    w.viscosity = ph.soundSpeed * ph.smoothing / (2.0f * P.rhoi);
    return w;
  }

  /// Given the fluid neighbours' acceleration `a` (and P's Shepard sums): the walls, the moving bodies,
  /// gravity, and the store.
  SPHXR_HD SPHXR_INLINE void End(int i, const ForceParticle& P, Vec3 a) const {
    if (P.nearWall) {
      const WallTerms w = Walls(P);
      const CubicSpline k = ph.kernel;
      const float eps = 0.01f * ph.smoothing * ph.smoothing;
      const Vec3 vi = P.vi;
      const float pTermI = P.pTermI;
      ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, grid.boundary, P.xi, [&](uint32_t j, Vec3 d) {
        const float r2 = Dot(d, d);
        if (r2 >= k.H2 || r2 == 0.0f) return;
        float term = ph.wallDensity ? ph.boundaryGradScale * (pTermI + grid.boundaryPressureTerm[j]) : w.pressureTerm;
        const float vx = Dot(vi, d);  // static walls: v_b = 0
        if (vx < 0.0f) term -= grid.boundaryAlpha[j] * w.viscosity * vx / (r2 + eps);
        a -= d * (grid.boundary[j].w * term * k.GradFactor(sqrtf(r2)));
      });
    }
    Store(i, P, a);
  }

  /// Given the fluid's and the walls' acceleration `a`: the moving bodies, gravity, and the store.
  SPHXR_HD SPHXR_INLINE void Store(int i, const ForceParticle& P, Vec3 a) const {
    // Moving boundaries (paddles): the walls' terms with the relative velocity v_i - v_b, so a moving
    // paddle pushes (pressure) and drags (viscosity) the water. BodyReactionStage applies the opposite.
    if (P.nearWall && grid.MovingNear(P.xi)) {
      const WallTerms w = Walls(P);
      const float pairTerm = P.pTermI + w.pWall / (P.rhoi * P.rhoi);
      if (bodyPressureTerm) bodyPressureTerm[i] = pairTerm;
      a -= BodyAcceleration(grid, ph, P.xi, P.vi, P.rhoi, pairTerm, grid.bodyStart, grid.bodyEnd);
    }
    a += ph.gravity;
    fluid.acceleration[i] = MakeVec4(a);
  }
};

}  // namespace sphxr::sim
