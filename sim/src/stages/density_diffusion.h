#pragma once
// Density as integrated state: the continuity equation with the delta-SPH density diffusion term
// (solver.density "delta_sph"; WCSPH only). Summation density (the default "summation") truncates the
// kernel at the free surface and flickers wherever a particle gains or loses a neighbour; the Tait
// equation turns that into a pressure field that jumps between 0 and tens of kPa. Integrating the density
// instead keeps a surface particle at rho0, and the diffusion term removes the high-frequency noise
// the continuity equation alone accumulates.
//
//   d rho_i / dt = sum_j m (v_i - v_j) . grad_i W_ij + sum_b Psi_b (v_i - v_b) . grad_i W_ib
//                + 2 delta h c0 sum_j (m / rho_j) [(rho_i - rho_j) - (rho_i^H - rho_j^H)] (x_ij . grad_i W_ij) / |x_ij|^2
//
// The first two sums are the time derivative of the summation density (Akinci et al. 2012's walls
// and bodies included), so without diffusion the two forms differ only by where they start: the
// continuity form starts at rho0 (the block's lattice) where the summation is truncated. The last sum is
// the density diffusion of Molteni & Colagrossi (2009, eq. 7; Antuono et al. 2010's delta-SPH) with
// delta = 0.1, over fluid neighbours only, with the hydrostatic correction of Fourtakas et al. (2019,
// eq. 12): the difference rho_i^H - rho_j^H that the Tait equation gives to a column at rest,
// rho0 ((1 + rho0 g.x_ij / B)^(1/gamma) - 1), is taken out, so still water keeps its hydrostatic density
// gradient instead of being diffused toward uniform density (which would lift the bottom layers'
// pressure off rho0 g depth). We use its first order, rho0 g.x_ij / c0^2: within 1e-6 relative for
// pairs within a support (rho0 g |x_ij| / B < 2e-3 in every scene here).
#include "stages/views.h"

namespace sphxr::sim {

/// delta of the diffusion term (Antuono et al. 2010: 0.1 for the usual resolutions).
inline constexpr float kDensityDiffusionDelta = 0.1f;

/// The density's rate of change of particle i into rate[i], after the integrator's kick and drift (the
/// positions and velocities of the step's end, so the density moves with the drift: with the step's
/// start velocities it lagged the drift by a step, the sound waves grew, and still water rang between
/// 0 and 4x its hydrostatic pressure). One work item per
/// particle, over the density stage's neighbour list (the cell scan when it overflowed: a pair that came
/// within the support during the drift is missed, at the kernel's edge where W and its gradient are
/// near zero); both backends.
struct DensityRateStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  float* rate;
  SPHXR_HD void operator()(int i) const {
    const Vec4 pi = fluid.position[i];
    const Vec3 xi = Xyz(pi);
    const Vec3 vi = Xyz(fluid.velocity[i]);
    const float rhoi = fluid.density[i];
    const CubicSpline k = ph.kernel;
    // 2 delta h c0 and rho0 / c0^2 (the hydrostatic difference per metre of g.x_ij).
    const float diffusion = 2.0f * kDensityDiffusionDelta * ph.smoothing * ph.soundSpeed;
    const float hydrostatic = ph.restDensity / (ph.soundSpeed * ph.soundSpeed);
    float continuity = 0.0f, diffused = 0.0f;
    auto fluidNeighbour = [&](uint32_t j, Vec3 d) {
      const float r2 = Dot(d, d);
      if (r2 >= k.H2 || r2 == 0.0f) return;
      const float f = k.GradFactor(sqrtf(r2));  // grad_i W_ij = d f, so (x_ij . grad_i W_ij) / r^2 = f
      const float rhoj = fluid.density[j];
      continuity += Dot(vi - Xyz(fluid.velocity[j]), d) * f;
      diffused += (rhoi - rhoj - hydrostatic * Dot(ph.gravity, d)) * f / rhoj;
    };
    ForEachFluidNeighbour(grid, fluid, list, i, xi, fluidNeighbour);
    float walls = 0.0f;
    if (pi.w != 0.0f) {  // a wall within the support (the density stage's flag)
      ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, grid.boundary, xi, [&](uint32_t b, Vec3 d) {
        const float r2 = Dot(d, d);
        if (r2 >= k.H2 || r2 == 0.0f) return;
        walls += grid.boundary[b].w * Dot(vi, d) * k.GradFactor(sqrtf(r2));  // static walls: v_b = 0
      });
      if (grid.MovingNear(xi)) {
        ForEachInCells(grid, grid.bodyStart, grid.bodyEnd, grid.body, xi, [&](uint32_t b, Vec3 d) {
          const float r2 = Dot(d, d);
          if (r2 >= k.H2 || r2 == 0.0f) return;
          walls += grid.body[b].w * Dot(vi - Xyz(grid.bodyVelocity[b]), d) * k.GradFactor(sqrtf(r2));
        });
      }
    }
    rate[i] = ph.mass * continuity + walls + diffusion * ph.mass * diffused;
  }
};

/// rho_i += dt rate_i (DensityRateStage, after the drift).
struct DensityIntegrateStage {
  FluidView fluid;
  const float* rate;
  float dt;
  SPHXR_HD void operator()(int i) const { fluid.density[i] += dt * rate[i]; }
};

}  // namespace sphxr::sim
