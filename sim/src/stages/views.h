#pragma once
// What every stage reads: plain views of raw pointers (FluidView, GridView, NeighbourList), the constants
// every stage shares (Physics), passed by value into host+device functors, and the loop over the 27 cells
// around a point. The stages themselves are one header each beside this one (stages.h lists them in
// the order of a step).
#include <cstdint>

#include "kernel.h"
#include "sphxr/common/assert.h"
#include "sphxr/sim/fields.h"
#include "sphxr/common/hd.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/vec.h"

namespace sphxr::sim {

inline constexpr uint32_t kEmptyCell = 0xffffffffu;

/// max(v, lo) and min(v, hi) as one comparison each. fmaxf and fminf are library calls on the host
/// without -ffast-math (measured: 3 % of a step on an AVX2 machine, from the cell look-ups). Where v is
/// NaN these give lo and hi, as fmaxf(v, lo) and fminf(v, hi) do; lo and hi must not be NaN.
SPHXR_HD SPHXR_INLINE float AtLeast(float v, float lo) { return v > lo ? v : lo; }
SPHXR_HD SPHXR_INLINE float AtMost(float v, float hi) { return v < hi ? v : hi; }
/// fmaxf(a, b) for the step's maxima, inline: the larger, and where one is NaN the other (both NaN:
/// NaN). fmaxf is a library call on the host, three per particle in the step's reduction (perf: 0.5 %
/// of a deep_tank step on one thread).
SPHXR_HD SPHXR_INLINE float MaxDroppingNaN(float a, float b) { return (a >= b || b != b) ? a : b; }

/// Raw pointers to every fluid field (generated from the field list).
struct FluidView {
#define SPHXR_VIEW_FIELD(type, name) type* name;
  SPHXR_FLUID_FIELDS(SPHXR_VIEW_FIELD)
#undef SPHXR_VIEW_FIELD
  int count;
};

/// Per-step scratch (not particle state, so not in the field list: rebuilt after every sort): the
/// fluid neighbours j != i within the support that the density stage found, in the order of its cell
/// scan, maxNeighbours slots per particle. The force stage walks this list instead of scanning the 27
/// cells again; a particle with more neighbours (count > maxNeighbours) falls back to the scan.
struct NeighbourList {
  uint32_t* index;  // [i * maxNeighbours + k]
  uint32_t* count;  // per particle; > maxNeighbours means "overflowed, scan the cells"
  int maxNeighbours;
};

/// Floats a particle takes in a lane-blocked pair cache (the CPU's SIMD passes of PBF and DFSPH keep each
/// listed pair's V grad W_ij as kLanes x, then kLanes y, then kLanes z) for `maxNeighbours` list slots,
/// in batches of up to 16 lanes (so at least what any CPU tier's kLanes needs).
SPHXR_HD SPHXR_INLINE int PairCacheStride(int maxNeighbours) { return (maxNeighbours + 15) / 16 * 16 * 3; }

/// The uniform grid over the domain: cells of size >= the kernel support; two particle sets
/// (fluid, re-sorted every step; boundary, sorted once) with their own cell ranges.
struct GridView {
  Vec3 origin;
  float cellSize;
  float invCellSize;
  int nx, ny, nz;
  const uint32_t* fluidStart;
  const uint32_t* fluidEnd;
  const uint32_t* boundaryStart;
  const uint32_t* boundaryEnd;
  const Vec4* boundary;  // xyz position, w = Psi_b (kg)
  const float* boundaryAlpha;  // artificial viscosity alpha of each boundary particle's wall
  const float* boundaryInvReference;  // per boundary particle: 1 / its rest-lattice fluid sum
  const float* boundaryPressureTerm;  // per boundary particle, this step: p_b / rho_b^2 (WallPressureStage)
  const uint8_t* boundaryNear; // per cell: 1 when a boundary particle lies in its 27 cells
  // Moving boundaries (paddles, stages/bodies.h): particles re-sorted every step with their own ranges.
  int bodyCount;                  // 0: no moving boundary; the pointers below are then unused
  const uint32_t* bodyStart;
  const uint32_t* bodyEnd;
  const Vec4* body;               // xyz world position, w = Psi_b (kg)
  const Vec4* bodyVelocity;       // xyz rigid velocity v + w x r (m/s), w = alpha of the body
  const uint8_t* movingNear;      // per cell: 1 when a moving boundary particle lies in its 27 cells

  SPHXR_HD SPHXR_INLINE bool MovingNear(Vec3 p) const {
    if (bodyCount == 0) return false;
    int cx, cy, cz;
    CellOf(p, &cx, &cy, &cz);
    return movingNear[Linear(cx, cy, cz)] != 0;
  }

  SPHXR_HD SPHXR_INLINE int Clampi(int v, int hi) const { return v < 0 ? 0 : (v > hi ? hi : v); }
  SPHXR_HD SPHXR_INLINE void CellOf(Vec3 p, int* cx, int* cy, int* cz) const {
    // AtMost takes 1e9 for a NaN: a NaN position stays inside the grid (validate mode names it later).
    *cx = Clampi(static_cast<int>(AtLeast(AtMost((p.x - origin.x) * invCellSize, 1e9f), 0.0f)), nx - 1);
    *cy = Clampi(static_cast<int>(AtLeast(AtMost((p.y - origin.y) * invCellSize, 1e9f), 0.0f)), ny - 1);
    *cz = Clampi(static_cast<int>(AtLeast(AtMost((p.z - origin.z) * invCellSize, 1e9f), 0.0f)), nz - 1);
  }
  SPHXR_HD SPHXR_INLINE uint32_t Linear(int cx, int cy, int cz) const {
    return static_cast<uint32_t>(cx + nx * (cy + ny * cz));
  }
  /// The cell coordinates of linear index c (Linear's inverse).
  SPHXR_HD SPHXR_INLINE void CellCoords(int c, int* cx, int* cy, int* cz) const {
    *cx = c % nx;
    *cy = (c / nx) % ny;
    *cz = c / (nx * ny);
  }
};

/// Calls f(j, xi - xj) for every particle j of `points` (ranges start/end) in the 27 cells around xi.
/// Cells whose nearest point is a cell size (>= the support radius) or more away from xi are skipped:
/// on average 6 of the 27 (edge cells are reachable with probability pi/4, corner cells pi/6), which
/// saves about a quarter of the distance tests. The skipped cells hold no particle within the support.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachInCells(const GridView& g, const uint32_t* start, const uint32_t* end,
                                           const Vec4* points, Vec3 xi, F&& f) {
  int cx, cy, cz;
  g.CellOf(xi, &cx, &cy, &cz);
  const int z0 = cz > 0 ? cz - 1 : 0, z1 = cz < g.nz - 1 ? cz + 1 : cz;
  const int y0 = cy > 0 ? cy - 1 : 0, y1 = cy < g.ny - 1 ? cy + 1 : cy;
  const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx < g.nx - 1 ? cx + 1 : cx;
  // Squared distance from xi to the near face of the cell at offset -1, 0, +1 along each axis. The
  // position inside the cell is clamped to the cell, so a clamped (out-of-grid) xi only culls less.
  const float cs = g.cellSize;
  auto gaps = [cs](float local, float* out) {
    const float t = AtMost(AtLeast(local, 0.0f), cs);
    out[0] = t * t;
    out[1] = 0.0f;
    out[2] = (cs - t) * (cs - t);
  };
  float gx[3], gy[3], gz[3];
  gaps(xi.x - g.origin.x - static_cast<float>(cx) * cs, gx);
  gaps(xi.y - g.origin.y - static_cast<float>(cy) * cs, gy);
  gaps(xi.z - g.origin.z - static_cast<float>(cz) * cs, gz);
  const float reach2 = cs * cs;
  for (int z = z0; z <= z1; ++z) {
    const float dz2 = gz[z - cz + 1];
    for (int y = y0; y <= y1; ++y) {
      const float dyz2 = dz2 + gy[y - cy + 1];
      if (dyz2 >= reach2) continue;
      const uint32_t row = g.Linear(0, y, z);
      for (int x = x0; x <= x1; ++x) {
        if (dyz2 + gx[x - cx + 1] >= reach2) continue;
        const uint32_t s = start[row + x];
        if (s == kEmptyCell) continue;
        const uint32_t e = end[row + x];
        for (uint32_t j = s; j < e; ++j) {
          const Vec4 pj = points[j];
          f(j, Vec3{xi.x - pj.x, xi.y - pj.y, xi.z - pj.z});
        }
      }
    }
  }
}

/// Calls f(j, xi - xj) for every fluid neighbour candidate j of particle i: its neighbour list (in list
/// order), or for a particle whose list overflowed (count > maxNeighbours) the 27 cells around xi.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachFluidNeighbour(const GridView& grid, const FluidView& fluid, const NeighbourList& list,
                                                  int i, Vec3 xi, F&& f) {
  const uint32_t found = list.count[i];
  if (found <= static_cast<uint32_t>(list.maxNeighbours)) {
    const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
    for (uint32_t n = 0; n < found; ++n) {
      const uint32_t j = slots[n];
      const Vec4 pj = fluid.position[j];
      f(j, Vec3{xi.x - pj.x, xi.y - pj.y, xi.z - pj.z});
    }
  } else {
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, xi, f);
  }
}

/// The diffuse particles' constants (stages/diffuse.h; Ihmsen et al. 2012 [IAAT12]), from the scene's
/// solver.diffuse_* keys. Unused unless `enabled`.
struct DiffuseConstants {
  bool enabled;
  int capacity;          // the pool's size (particles)
  float trappedAir;      // k_ta, diffuse particles per second at I_ta = I_k = 1          [IAAT12 eq. 8]
  float waveCrest;       // k_wc, the same for I_wc
  float trappedAirMin;   // tau_ta: the trapped-air potential's range, m/s                [IAAT12 eq. 1-2]
  float trappedAirMax;
  float waveCrestMin;    // tau_wc: the wave-crest potential's range (a curvature, no unit) [IAAT12 eq. 4-6]
  float waveCrestMax;
  float energyMin;       // tau_k: the kinetic energy's range, J/kg (1/2 |v|^2)             [IAAT12 eq. 7]
  float energyMax;
  float lifetime;        // s: a particle's lifetime is drawn in [0.5, 1] x this
  float buoyancy;        // k_b: a bubble's buoyancy, in units of -g                      [IAAT12 eq. 12]
  float drag;            // k_d: the fraction of a bubble's velocity difference to the water removed per step
  int sprayBelow;        // fewer fluid neighbours: spray
  int bubbleAbove;       // more: an air bubble; between: foam
  float radius;          // m, r_V: the spawning cylinder's radius (half a spacing)       [IAAT12 sec. 4.1]
};

/// The constants every stage shares, computed once per scene (Solver::Create, and again when a setting
/// changes at run time); a step sets only its own number (step, reuseSyncStep). A solver's own constants
/// are its own (solvers/<method>/<method>_constants.h). Passed by value into every stage.
struct Physics {
  CubicSpline kernel;
  float mass;           // kg per fluid particle
  float restDensity;
  float invRestDensity;
  float boundaryGamma;  // Psi_b = gamma rho0 V_b: flat-wall rest-density correction (sampling.h)
  float boundaryGradScale;  // gamma_grad / gamma: flat-wall pressure-gradient consistency (sampling.h)
  int maxNeighbours;    // neighbour-list slots per particle (NeighbourList)
  // Activity-based reuse (Huang et al. 2013, section 3.3); used only when the reuse stage runs.
  bool reuseEnabled;
  float reuseDelta1;
  float reuseDelta2;
  float reuseThreshold;
  int reuseIdle;
  float reuseInvPressureScale;  // 1 / P_pc
  float reuseCellCount;         // N_CPN
  bool reuseSyncStep;           // this step's number is a multiple of IDLE + 1 (the impulse hold's schedule)
  bool continuityDensity;       // solver.density delta_sph: density is state (stages/density_diffusion.h)
  bool wallDensity;             // walls with their own density (WallPressureStage), else mirrored pressure
  float bodyGradScale;          // as boundaryGradScale, for the one-sheet shells of moving bodies
  float bodyClearance;          // m outside a moving body's solid where push-out puts a fluid particle
  float stiffness;      // Tait B
  float exponent;       // Tait gamma
  float soundSpeed;     // sqrt(B gamma / rho0)
  float smoothing;      // h = support / 2, used by the viscosity term
  float alpha;          // fluid-fluid artificial viscosity
  Vec3 gravity;
  Vec3 domainMin;       // clamp box for fluid particles
  Vec3 domainMax;
  // Obstacles (static boxes), each grown by the same inset as the clamp box: a fluid particle inside
  // one is put back on its nearest face (ClampOutOfObstacles).
  int obstacleCount;
  Vec3 obstacleMin[kMaxObstacles];
  Vec3 obstacleMax[kMaxObstacles];
  // The walls' contact force (stages/contact.h): the zone's width before the clamp box (m) and the
  // acceleration at its floor (m/s^2; 0: tank.wall_contact off); the top face counts when the tank is closed.
  float contactWidth;
  float contactStrength;
  bool contactBelowRestOnly;  // the contact acts only on particles lighter than rho0 (DFSPH; contact.h)
  bool closedTop;
  float volume;                 // m / rho0, each fluid particle's rest volume
  // post-step stages (post_step.h)
  DiffuseConstants diffuse;     // spray, foam and bubbles (stages/diffuse.h)
  int64_t step;                 // this step's number since the run began (SolverClock::steps + 1): seeds the
                                // diffuse particles' random numbers, so a restored run draws the same ones
};

}  // namespace sphxr::sim
