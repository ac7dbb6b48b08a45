#pragma once
// The walls' own stages: each wall particle's volume (once) and, under tank.wall_pressure
// "wall_density", its pressure from the fluid around it (every step; docs/design/walls.md). The
// CPU's SIMD form of the latter is cpu/walls.h.
#include <cstdint>

#include "stages/density.h"
#include "stages/grid.h"
#include "stages/views.h"

namespace sphxr::sim {

// ---- wall pressure (every step): each wall particle's own density from the fluid around it -----------
/// rho_b = rho0 sum_f W_bf / R_b with R_b the same sum over the fluid's rest lattice filling the tank
/// (sampling.h, WallInverseReferences): the wall particle is as compressed as the water beside it.
/// p_b = Tait(rho_b). The force's pair term p_i/rho_i^2 + p_b/rho_b^2 is then the derivative of an
/// energy (the fluid's and the walls' own, each a function of the particle positions only), so still
/// water comes to rest. Mirroring (p_b = p_i) is not such a derivative and pumps a ~1 cm/s circulation
/// (docs/dev/physics.md, "Hydrostatics").
/// One work item per grid cell holding wall particles (`cells`): a cell with no fluid in its 27 cells
/// (most of a tank's walls) writes 0 for its particles after 27 look-ups, instead of every particle
/// scanning its own 27 cells.
struct WallPressureStage {
  GridView grid;
  FluidView fluid;
  Physics ph;
  const uint32_t* cells;  // linear indices of the cells that hold wall particles
  float* out;  // p_b / rho_b^2
  SPHXR_HD void operator()(int k) const {
    const uint32_t c = cells[k];
    const bool fluidNear = AnyInNeighbourCells(grid, grid.fluidStart, static_cast<int>(c));
    for (uint32_t b = grid.boundaryStart[c]; b < grid.boundaryEnd[c]; ++b) {
      out[b] = fluidNear ? Particle(static_cast<int>(b)) : 0.0f;
    }
  }
  SPHXR_HD SPHXR_INLINE float Particle(int b) const {
    const Vec3 xb = Xyz(grid.boundary[b]);
    const CubicSpline k = ph.kernel;
    float sum = 0.0f;
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, xb, [&](uint32_t, Vec3 d) {
      const float r2 = Dot(d, d);
      if (r2 < k.H2) sum += k.W(sqrtf(r2));
    });
    return FromSum(b, sum);
  }
  /// p_b / rho_b^2 of wall particle b from its kernel sum over the fluid.
  SPHXR_HD SPHXR_INLINE float FromSum(int b, float sum) const {
    const float rho = ph.restDensity * sum * grid.boundaryInvReference[b];
    const float p = TaitPressure(ph, rho);
    return p > 0.0f ? p / (rho * rho) : 0.0f;
  }
};

// ---- boundary volumes (once, Akinci et al. 2012 eq. 4: V_b = 1 / sum_k W_bk; Psi_b = gamma rho0 V_b) --
struct BoundaryVolumeStage {
  GridView grid;
  const Vec4* in;   // sorted boundary positions
  Vec4* out;        // same, with w = Psi_b = rho0 V_b
  float psiScale;  // gamma rho0
  CubicSpline kernel;
  SPHXR_HD void operator()(int b) const {
    const Vec3 xb = Xyz(in[b]);
    float sum = 0.0f;
    const CubicSpline k = kernel;
    ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, in, xb, [&](uint32_t, Vec3 d) {
      const float r2 = Dot(d, d);
      if (r2 < k.H2) sum += k.W(sqrtf(r2));
    });
    out[b] = MakeVec4(xb, psiScale / sum);
  }
};

}  // namespace sphxr::sim
