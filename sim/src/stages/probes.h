#pragma once
// The probes' stage (sphxr/sim/probes.h): one work item per pressure sensor or level gauge, each scanning
// the 27 cells around its point(s) of the neighbour grid, host+device like every stage of stages.h.
// backend_impl.h launches it in the step, where positions, densities, pressures and the grid belong to
// one state (the start of the step), and on demand (Backend::SampleProbesNow, after a re-grid).
//
// Output per probe, two floats (the host turns them into readings, sim/src/probes.cpp):
//   pressure sensor k:  out[2k] = sum_j V_j p_j W(x - x_j),  out[2k + 1] = sum_j V_j W(x - x_j)
//   level gauge k:      out[2P + 2k] = the height of the crossing, out[2P + 2k + 1] = 1 where found, else 0
// with V_j = m / rho_j and P the number of pressure sensors.
#include <cstdint>

#include "sphxr/sim/probes.h"
#include "stages/views.h"

namespace sphxr::sim {

/// A level gauge as the stage sees it: the line and the sampling steps (m).
struct ProbeLine {
  float x, z, bottom, top;
  float coarse, fine;  // m: kLevelCoarse and kLevelFine spacings
};

struct ProbeStage {
  GridView grid;
  FluidView fluid;
  Physics ph;
  const Vec4* points;  // pressure sensors: xyz, the point in the water
  int pointCount;
  const ProbeLine* lines;
  float* out;

  SPHXR_HD void operator()(int k) const {
    if (k < pointCount) {
      float weighted = 0.0f, sum = 0.0f;
      Sums(Xyz(points[k]), &weighted, &sum);
      out[2 * k] = weighted;
      out[2 * k + 1] = sum;
      return;
    }
    const int g = k - pointCount;
    float level = 0.0f;
    const bool found = Level(lines[g], &level);
    out[2 * k] = level;
    out[2 * k + 1] = found ? 1.0f : 0.0f;
  }

  /// sum_j V_j p_j W and sum_j V_j W at x, in the order of the cell scan.
  SPHXR_HD SPHXR_INLINE void Sums(Vec3 x, float* weighted, float* sum) const {
    const CubicSpline k = ph.kernel;
    float pw = 0.0f, s = 0.0f;
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, x, [&](uint32_t j, Vec3 d) {
      const float r2 = Dot(d, d);
      if (r2 >= k.H2) return;
      const float vw = ph.mass / fluid.density[j] * k.W(sqrtf(r2));
      pw += vw * fluid.pressure[j];
      s += vw;
    });
    *weighted = pw;
    *sum = s;
  }

  SPHXR_HD SPHXR_INLINE float Fraction(const ProbeLine& line, float y) const {
    float pw, s;
    Sums(Vec3{line.x, y, line.z}, &pw, &s);
    return s;
  }

  /// The first height, going up the line, where the fluid fraction falls below kLevelFraction after
  /// having reached it: coarse steps, the step of the crossing again in fine steps, and the crossing by
  /// linear interpolation between the two fine samples around it. Water up to the line's top reads the
  /// top; a line whose fraction never reaches kLevelFraction is not found (dry).
  SPHXR_HD SPHXR_INLINE bool Level(const ProbeLine& line, float* level) const {
    const float half = kLevelFraction;
    bool wet = false;
    float y = line.bottom;
    float phi = Fraction(line, y);
    if (phi >= half) wet = true;
    while (y < line.top) {
      const float yNext = AtMost(y + line.coarse, line.top);
      const float phiNext = Fraction(line, yNext);
      if (!wet) {
        wet = phiNext >= half;
      } else if (phiNext < half) {
        // Refine the step [y, yNext] from its start: the first fine sample below the fraction.
        float ya = y, phiA = phi;
        for (;;) {
          const float yb = AtMost(ya + line.fine, yNext);
          const float phiB = yb >= yNext ? phiNext : Fraction(line, yb);
          if (phiB < half) {
            *level = ya + (yb - ya) * (phiA - half) / (phiA - phiB);
            return true;
          }
          ya = yb;
          phiA = phiB;
        }
      }
      y = yNext;
      phi = phiNext;
    }
    *level = line.top;
    return wet;
  }
};

}  // namespace sphxr::sim
