#pragma once
// Stage 4 of a step: summation density rho_i = sum_j m W_ij + sum_b Psi_b W_ib (Akinci et al. 2012,
// eq. 4-5) and the Tait pressure p_i = B ((rho_i/rho0)^gamma - 1), clamped at 0 (Becker & Teschner
// 2007, eq. 7). The CPU's SIMD form is cpu/density_blocks.h.
#include <cstdint>

#include "stages/views.h"

namespace sphxr::sim {

SPHXR_HD SPHXR_INLINE float TaitPressure(const Physics& ph, float density) {
  const float ratio = density * ph.invRestDensity;
  float power;
  if (ph.exponent == 7.0f) {
    const float r2 = ratio * ratio;
    power = r2 * r2 * r2 * ratio;
  } else {
    power = powf(ratio, ph.exponent);
  }
  const float p = ph.stiffness * (power - 1.0f);
  return p > 0.0f ? p : 0.0f;  // clamp: no tension at the free surface (B&T 2007)
}


// ---- stage 4: density and pressure ---------------------------------------------------------------
/// One work item per particle (the CUDA backend). The CPU backend runs Finish (and the same sums, in
/// SIMD) from DensityBlockStage (cpu/density.h), which tests one candidate against up to 16 particles
/// at once: the same neighbour lists, densities equal to rounding (tests/sim/cpu_stages_test.cpp).
struct DensityStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  const int* gate = nullptr;  // a device flag (PressureSolver::GridGate): nothing where it is 0; nullptr: always
  SPHXR_HD void operator()(int i) const {
    SPHXR_ASSERT(i >= 0 && i < fluid.count);  // an entry of the compacted list, on CUDA a thread's index
    if (gate && *gate == 0) return;
    const Vec3 xi = Xyz(fluid.position[i]);
    float sumFluid = 0.0f;
    uint32_t found = 0;
    uint32_t* slots = Slots(i);
    const uint32_t self = static_cast<uint32_t>(i);
    const CubicSpline k = ph.kernel;
    const uint32_t capacity = static_cast<uint32_t>(list.maxNeighbours);
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, xi, [&](uint32_t j, Vec3 d) {
      const float r2 = Dot(d, d);
      if (r2 < k.H2) {
        sumFluid += k.W(sqrtf(r2));
        if (j != self) {  // the neighbour list, counted past the capacity (the force stage then scans)
          if (found < capacity) slots[found] = j;
          ++found;
        }
      }
    });
    Finish(i, xi, sumFluid, found);
  }
  SPHXR_HD SPHXR_INLINE uint32_t* Slots(int i) const {
    return list.index + static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
  }
  /// The walls' and bodies' sums, then density, pressure and p/rho^2 of particle i.
  SPHXR_HD SPHXR_INLINE void Finish(int i, Vec3 xi, float sumFluid, uint32_t found) const {
    Complete(i, xi, sumFluid, WallSum(xi), found);
  }
  /// sum_b Psi_b W_ib over the walls' particles around xi, in the order of the cell scan (0 when no
  /// wall particle lies in xi's 27 cells).
  SPHXR_HD SPHXR_INLINE float WallSum(Vec3 xi) const {
    const CubicSpline k = ph.kernel;
    float sum = 0.0f;
    int cx, cy, cz;
    grid.CellOf(xi, &cx, &cy, &cz);
    if (grid.boundaryNear[grid.Linear(cx, cy, cz)]) {
      ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, grid.boundary, xi, [&](uint32_t j, Vec3 d) {
        const float r2 = Dot(d, d);
        if (r2 < k.H2) sum += grid.boundary[j].w * k.W(sqrtf(r2));
      });
    }
    return sum;
  }
  /// Given the fluid's and the walls' sums: the moving bodies' sum, then density, pressure, p/rho^2.
  SPHXR_HD SPHXR_INLINE void Complete(int i, Vec3 xi, float sumFluid, float sumWall, uint32_t found) const {
    const CubicSpline k = ph.kernel;
    list.count[i] = found;
    float sumBoundary = sumWall;
    if (grid.MovingNear(xi)) {  // moving boundaries (paddles): the same sum (Akinci et al. 2012, eq. 5)
      ForEachInCells(grid, grid.bodyStart, grid.bodyEnd, grid.body, xi, [&](uint32_t j, Vec3 d) {
        const float r2 = Dot(d, d);
        if (r2 < k.H2) sumBoundary += grid.body[j].w * k.W(sqrtf(r2));
      });
    }
    // delta_sph: the density is integrated state (stages/density_diffusion.h); the sums above still give
    // the neighbour list and the wall flag.
    const float rho = ph.continuityDensity ? fluid.density[i] : ph.mass * sumFluid + sumBoundary;
    fluid.density[i] = rho;
    const float pressure = TaitPressure(ph, rho);
    fluid.pressure[i] = pressure;
    fluid.pressureTerm[i] = pressure / (rho * rho);
    // Remember whether a wall is within the support: the force stage then skips the wall term, and the
    // Shepard pressure average it needs, for the particles away from walls (most of them).
    fluid.position[i].w = sumBoundary > 0.0f ? 1.0f : 0.0f;
  }
};

}  // namespace sphxr::sim
