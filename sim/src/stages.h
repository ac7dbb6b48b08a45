#pragma once
// The per-particle stages of one WCSPH step, written once as host+device functors over plain views of
// raw pointers. backend_impl.h launches them with thrust on the OpenMP system (CPU backend) or the CUDA
// system (CUDA backend): the physics has exactly one source.
//
// Step (Becker & Teschner 2007, "Weakly compressible SPH for free surface flows"):
//   1. cells:     Morton code of each fluid particle's cell                  (Huang et al. 2013, §3.1)
//   2. sort:      stable radix/merge sort by code; gather every field         (fields.h list)
//   3. grid:      cellStart/cellEnd per cell from the sorted codes
//   4. density:   rho_i = sum_j m W_ij + sum_b Psi_b W_ib                     (Akinci et al. 2012, eq. 4-5)
//                 p_i = B ((rho_i/rho0)^gamma - 1), clamped at 0             (B&T 2007, eq. 7)
//   5. forces:    a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) gradW_ij  (B&T 2007, eq. 6 and 10)
//                       -sum_b Psi_b (s (p_i + p_b)/rho_i^2 + Pi_ib) gradW_ib (Akinci et al. 2012, eq. 10-11, in the
//                             symmetric form; p_b = max(p_i, Shepard average of p around i); s: flat-wall
//                             gradient consistency, sampling.h)
//                       + g
//                 Pi_ij = -2 alpha c h min(v_ij.x_ij, 0) / ((|x_ij|^2 + 0.01 h^2)(rho_i + rho_j))  (Monaghan 1992)
//   6. integrate: symplectic Euler v += dt a, x += dt v; particles leaving the domain are clamped back
//                 and counted.
#include <cstdint>

#include "kernel.h"
#include "morton.h"
#include "sphxr/common/assert.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/hd.h"
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
  // Moving boundaries (paddles, body_stages.h): particles re-sorted every step with their own ranges.
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

/// Constants of one step, passed by value into every stage.
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
  // DFSPH (dfsph_solver.h); unused by WCSPH.
  bool dfsph;                   // SolverMethod::kDfsph
  float volume;                 // m / rho0, each fluid particle's rest volume
  float densityTolerance;       // mean compression (fraction) at which the density solve stops
  float divergenceTolerance;    // mean compression per step (fraction) at which the divergence solve stops
  int minIterations;
  int maxIterations;
  int maxDivergenceIterations;  // 0: no divergence solve
};

/// Puts a particle that left the domain back on its edge with the outward velocity removed; true when
/// it did (the step counts them: acceleration.w, StepReductionOp).
SPHXR_HD SPHXR_INLINE bool ClampToDomain(const Physics& ph, Vec4* x, Vec4* v) {
  bool clamped = false;
  if (x->x < ph.domainMin.x) { x->x = ph.domainMin.x; if (v->x < 0.0f) v->x = 0.0f; clamped = true; }
  if (x->x > ph.domainMax.x) { x->x = ph.domainMax.x; if (v->x > 0.0f) v->x = 0.0f; clamped = true; }
  if (x->y < ph.domainMin.y) { x->y = ph.domainMin.y; if (v->y < 0.0f) v->y = 0.0f; clamped = true; }
  if (x->y > ph.domainMax.y) { x->y = ph.domainMax.y; if (v->y > 0.0f) v->y = 0.0f; clamped = true; }
  if (x->z < ph.domainMin.z) { x->z = ph.domainMin.z; if (v->z < 0.0f) v->z = 0.0f; clamped = true; }
  if (x->z > ph.domainMax.z) { x->z = ph.domainMax.z; if (v->z > 0.0f) v->z = 0.0f; clamped = true; }
  return clamped;
}

/// Puts a particle inside an obstacle (grown by the clamp inset) on the obstacle's nearest face, with the
/// velocity into the obstacle removed; true when it did. The obstacle's boundary particles should hold
/// the water; this is the safety net, as the domain clamp is for the tank.
SPHXR_HD SPHXR_INLINE bool ClampOutOfObstacles(const Physics& ph, Vec4* x, Vec4* v) {
  bool clamped = false;
  for (int k = 0; k < ph.obstacleCount; ++k) {
    const Vec3 lo = ph.obstacleMin[k], hi = ph.obstacleMax[k];
    if (!(x->x > lo.x && x->x < hi.x && x->y > lo.y && x->y < hi.y && x->z > lo.z && x->z < hi.z)) continue;
    // The face the particle is nearest: axis a, side (lo or hi).
    const float depth[6] = {x->x - lo.x, hi.x - x->x, x->y - lo.y, hi.y - x->y, x->z - lo.z, hi.z - x->z};
    int face = 0;
    for (int f = 1; f < 6; ++f) {
      if (depth[f] < depth[face]) face = f;
    }
    float* xs[3] = {&x->x, &x->y, &x->z};
    float* vs[3] = {&v->x, &v->y, &v->z};
    const float bound[6] = {lo.x, hi.x, lo.y, hi.y, lo.z, hi.z};
    const int axis = face / 2;
    *xs[axis] = bound[face];
    // Low face: the outward direction is -axis, so velocity along +axis goes into the box.
    if ((face % 2 == 0) ? (*vs[axis] > 0.0f) : (*vs[axis] < 0.0f)) *vs[axis] = 0.0f;
    clamped = true;
  }
  return clamped;
}

/// The clamp site (params.h kClampSites) that put particle x where it is after a clamp: the tank face
/// it sits on, else the obstacle on whose grown face it sits; -1 when none (a moving body pushed it on).
SPHXR_HD SPHXR_INLINE int ClampSiteOf(const Physics& ph, Vec3 x) {
  if (x.x == ph.domainMin.x) return 0;
  if (x.x == ph.domainMax.x) return 1;
  if (x.y == ph.domainMin.y) return 2;
  if (x.y == ph.domainMax.y) return 3;
  if (x.z == ph.domainMin.z) return 4;
  if (x.z == ph.domainMax.z) return 5;
  for (int k = 0; k < ph.obstacleCount; ++k) {
    const Vec3 lo = ph.obstacleMin[k], hi = ph.obstacleMax[k];
    const bool inside = x.x >= lo.x && x.x <= hi.x && x.y >= lo.y && x.y <= hi.y && x.z >= lo.z && x.z <= hi.z;
    const bool onFace = x.x == lo.x || x.x == hi.x || x.y == lo.y || x.y == hi.y || x.z == lo.z || x.z == hi.z;
    if (inside && onFace) return kTankFaces + k;
  }
  return -1;
}

/// The end of every integrator: x += dt v, the domain and obstacle clamps (flagged in acceleration.w, so
/// that the step reports how many were clamped, and where), and the store of particle i's position,
/// velocity and acceleration.
SPHXR_HD SPHXR_INLINE void DriftAndStore(const FluidView& fluid, const Physics& ph, float dt, int i, Vec4 x, Vec4 v,
                                         Vec4 a) {
  x.x += dt * v.x;
  x.y += dt * v.y;
  x.z += dt * v.z;
  bool clamped = ph.obstacleCount > 0 && ClampOutOfObstacles(ph, &x, &v);
  clamped = ClampToDomain(ph, &x, &v) || clamped;
  a.w = clamped ? 1.0f : 0.0f;
  fluid.acceleration[i] = a;
  fluid.velocity[i] = v;
  fluid.position[i] = x;
}

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

// ---- stage 1: cell codes -------------------------------------------------------------------------
struct CellCodeStage {
  GridView grid;
  const Vec4* position;
  uint32_t* keys;
  uint32_t* order;
  SPHXR_HD void operator()(int i) const {
    int cx, cy, cz;
    grid.CellOf(Xyz(position[i]), &cx, &cy, &cz);
    keys[i] = MortonEncode(static_cast<uint32_t>(cx), static_cast<uint32_t>(cy), static_cast<uint32_t>(cz));
    order[i] = static_cast<uint32_t>(i);
  }
};

// ---- stage 3: cell ranges from sorted particles --------------------------------------------------
struct CellRangeStage {
  GridView grid;
  const Vec4* position;  // sorted
  const uint32_t* keys;  // sorted
  uint32_t* start;
  uint32_t* end;
  int count;
  SPHXR_HD void operator()(int i) const {
    const uint32_t key = keys[i];
    if (i > 0 && keys[i - 1] == key && i < count - 1 && keys[i + 1] == key) return;
    int cx, cy, cz;
    grid.CellOf(Xyz(position[i]), &cx, &cy, &cz);
    const uint32_t cell = grid.Linear(cx, cy, cz);
    if (i == 0 || keys[i - 1] != key) start[cell] = static_cast<uint32_t>(i);
    if (i == count - 1 || keys[i + 1] != key) end[cell] = static_cast<uint32_t>(i + 1);
  }
};

/// f(n) for the linear index n of each of the 27 cells around cell (cx, cy, cz) that lie in the grid,
/// in z, y, x order.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachCellAround(const GridView& grid, int cx, int cy, int cz, F&& f) {
  for (int z = cz - 1; z <= cz + 1; ++z)
    for (int y = cy - 1; y <= cy + 1; ++y)
      for (int x = cx - 1; x <= cx + 1; ++x) {
        if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz) continue;
        f(grid.Linear(x, y, z));
      }
}

// ---- cells near the boundary (once): any boundary particle in the 27 cells around cell c ------------
/// Whether any of the 27 cells around linear cell c (within the grid) is non-empty in `start`.
SPHXR_HD SPHXR_INLINE bool AnyInNeighbourCells(const GridView& grid, const uint32_t* start, int c) {
  int cx, cy, cz;
  grid.CellCoords(c, &cx, &cy, &cz);
  bool any = false;
  ForEachCellAround(grid, cx, cy, cz, [&](uint32_t n) {
    if (start[n] != kEmptyCell) any = true;
  });
  return any;
}

/// Predicate for compacting cell indices: the cell's start is not kEmptyCell.
struct NonEmptyCell {
  SPHXR_HD bool operator()(uint32_t start) const { return start != kEmptyCell; }
};

struct BoundaryNearStage {
  GridView grid;
  uint8_t* out;
  SPHXR_HD void operator()(int c) const { out[c] = AnyInNeighbourCells(grid, grid.boundaryStart, c) ? 1 : 0; }
};

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

// ---- stage 3b: activity (reuse on) ---------------------------------------------------------------
/// Each cell's particles, fluid and wall (reuse only; every cell, empty ones 0): what CellBoxSumStage sums.
/// Wall particles count too: water along a wall is crowded, not sparse, although the cells beyond the
/// wall hold no fluid.
struct CellCountStage {
  GridView grid;
  uint32_t* count;
  SPHXR_HD void operator()(int c) const {
    uint32_t particles = 0;
    if (grid.fluidStart[c] != kEmptyCell) particles += grid.fluidEnd[c] - grid.fluidStart[c];
    if (grid.boundaryStart[c] != kEmptyCell) particles += grid.boundaryEnd[c] - grid.boundaryStart[c];
    count[c] = particles;
  }
};

/// One of the three passes of the sum of CellCountStage's counts over the 27 cells around every cell
/// (reuse only): the activity stage's crowding N_i. Along `axis` (0 x, 1 y, 2 z), out[c] = in[c - s] +
/// in[c] + in[c + s], s the axis' stride, a neighbour outside the grid counting 0; the x, y and z passes
/// in turn give each cell the particles of its 27 cells exactly (integers), with 9 loads per cell and no
/// division. One work item per row of cells along x (row = cy + ny cz). Summing 27 cells per fluid cell
/// instead took 3.2 % of a `dam_break_1m` step on an AVX-512 machine; per particle, 2.3 ms of a 39 ms
/// one-thread `deep_tank` step on an AVX2 machine.
struct CellBoxSumStage {
  GridView grid;
  const uint32_t* in;
  uint32_t* out;
  int axis;
  SPHXR_HD void operator()(int row) const {
    const int nx = grid.nx;
    const size_t first = static_cast<size_t>(row) * static_cast<size_t>(nx);
    const uint32_t* mid = in + first;
    uint32_t* o = out + first;
    if (axis == 0) {
      if (nx == 1) {
        o[0] = mid[0];
        return;
      }
      o[0] = mid[0] + mid[1];
      for (int x = 1; x < nx - 1; ++x) o[x] = mid[x - 1] + mid[x] + mid[x + 1];
      o[nx - 1] = mid[nx - 2] + mid[nx - 1];
      return;
    }
    const int cy = row % grid.ny, cz = row / grid.ny;
    const size_t stride = axis == 1 ? static_cast<size_t>(nx) : static_cast<size_t>(nx) * static_cast<size_t>(grid.ny);
    const bool below = axis == 1 ? cy > 0 : cz > 0;
    const bool above = axis == 1 ? cy + 1 < grid.ny : cz + 1 < grid.nz;
    if (below && above) {
      const uint32_t* lo = mid - stride;
      const uint32_t* hi = mid + stride;
      for (int x = 0; x < nx; ++x) o[x] = lo[x] + mid[x] + hi[x];
    } else if (below || above) {
      const uint32_t* other = below ? mid - stride : mid + stride;
      for (int x = 0; x < nx; ++x) o[x] = other[x] + mid[x];
    } else {
      for (int x = 0; x < nx; ++x) o[x] = mid[x];
    }
  }
};

// Idle count IC: -1 active. A particle with IC > 0 reuses this step (density, pressure, acceleration
// stay as they are) and counts down; at IC = 0, or when active, it computes this step and is classified
// with its previous pressure and the crowding of its cells: ACT_i < T gives IC = IDLE, else -1. So a
// particle never reuses more than IDLE consecutive steps. After this stage, "computes this step" is
// exactly IC < 0 or IC == IDLE (ComputesThisStep).
struct ActivityStage {
  GridView grid;
  FluidView fluid;
  Physics ph;
  const uint32_t* crowd;  // CellBoxSumStage's three passes: the particles of the 27 cells around each cell
  SPHXR_HD void operator()(int i) const {
    // Paddles: a particle near a moving boundary always computes (its neighbourhood changes every step).
    if (grid.MovingNear(Xyz(fluid.position[i]))) {
      fluid.idle[i] = -1;
      return;
    }
    const int32_t ic = fluid.idle[i];
    if (ic > 0) {  // reuses this step
      fluid.idle[i] = ic - 1;
      return;
    }
    // The impulse hold's synchronised schedule: particles go inactive together, on every (IDLE + 1)-th
    // step, so a calm region reuses over the same steps and computes on the same step (docs/design/impulse_hold.md).
    // On the other steps the crowding is not computed (BackendImpl::Step) and not read.
    if (!ph.reuseSyncStep) {
      fluid.idle[i] = -1;
      return;
    }
    int cx, cy, cz;
    grid.CellOf(Xyz(fluid.position[i]), &cx, &cy, &cz);
    // The mean over all 27 cells, those outside the grid as empty: a particle there is at an edge.
    const float meanCount = static_cast<float>(crowd[grid.Linear(cx, cy, cz)]) / 27.0f;
    const float act = ph.reuseDelta1 * fluid.pressure[i] * ph.reuseInvPressureScale +
                      ph.reuseDelta2 * ph.reuseCellCount / AtLeast(meanCount, 1e-6f);
    fluid.idle[i] = (act < ph.reuseThreshold && ph.reuseIdle > 0) ? ph.reuseIdle : -1;
  }
};

struct ComputesThisStep {
  const int32_t* idle;
  int32_t idleSteps;
  SPHXR_HD bool operator()(int i) const { return idle[i] < 0 || idle[i] == idleSteps; }
};

/// 1 for a particle i < n whose density is computed this step, else 0 (also for i = n: the CPU density
/// blocks' rank scan runs over n + 1 items, cpu_stages.h BlockSet).
struct ComputeFlag {
  ComputesThisStep density;
  int n;
  SPHXR_HD uint32_t operator()(int i) const { return i < n && density(i) ? 1u : 0u; }
};

/// Runs a per-particle stage over a compacted list of particle indices.
template <class Stage>
struct OverList {
  const uint32_t* list;
  Stage stage;
  SPHXR_HD void operator()(int k) const { stage(static_cast<int>(list[k])); }
};

// ---- stage 4: density and pressure ---------------------------------------------------------------
/// One work item per particle (the CUDA backend). The CPU backend runs Finish (and the same sums, in
/// SIMD) from DensityBlockStage (cpu_stages.h), which tests one candidate against up to 16 particles
/// at once: the same neighbour lists, densities equal to rounding (tests/sim/cpu_stages_test.cpp).
struct DensityStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  SPHXR_HD void operator()(int i) const {
    SPHXR_ASSERT(i >= 0 && i < fluid.count);  // an entry of the compacted list, on CUDA a thread's index
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
/// SIMD sum over the neighbour list (ForceListStage, cpu_stages.h).
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
    const uint32_t found = list.count[i];
    if (found <= static_cast<uint32_t>(list.maxNeighbours)) {
      const uint32_t* slots = list.index + static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
      for (uint32_t n = 0; n < found; ++n) {
        const uint32_t j = slots[n];
        const Vec4 pj = fluid.position[j];
        fluidNeighbour(j, Vec3{xi.x - pj.x, xi.y - pj.y, xi.z - pj.z});
      }
    } else {
      ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, xi, fluidNeighbour);
    }
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

// acceleration.w after a step: 1 clamped into the domain (IntegrateStage), 2 pushed out of a moving
// body (PushOutStage, body_stages.h), 3 both. StepReductionOp counts them; tests read them too.
SPHXR_HD SPHXR_INLINE bool WasClamped(float w) { return w == 1.0f || w == 3.0f; }
SPHXR_HD SPHXR_INLINE bool WasPushed(float w) { return w >= 2.0f; }

// ---- stage 6: symplectic Euler and domain clamp --------------------------------------------------
struct IntegrateStage {
  FluidView fluid;
  Physics ph;
  float dt;
  SPHXR_HD void operator()(int i) const {
    Vec4 a = fluid.acceleration[i];
    Vec4 v = fluid.velocity[i];
    Vec4 x = fluid.position[i];
    // The impulse hold (docs/design/impulse_hold.md): a particle that computed this step and reuses the next IDLE
    // steps takes all their kicks now, (IDLE + 1) dt a, and drifts while it reuses. For a calm region
    // on the synchronised schedule that is symplectic Euler at step (IDLE + 1) dt for its forces:
    // stable where that step meets the pressure waves' limit, and conserving phase-space area, where
    // applying the held a on every step pumps energy into every sound mode.
    float kick = dt;
    if (ph.reuseEnabled && ph.reuseIdle > 0) {
      const int32_t ic = fluid.idle[i];
      if (ic == ph.reuseIdle) {
        kick = dt * static_cast<float>(ph.reuseIdle + 1);
      } else if (ic >= 0) {
        kick = 0.0f;
      }
    }
    v.x += kick * a.x;
    v.y += kick * a.y;
    v.z += kick * a.z;
    DriftAndStore(fluid, ph, dt, i, x, v, a);
  }
};

// ---- settling: FIRE (Bitzek et al. 2006) on the solver's own steps (Solver::Settle) ----------------
/// Sums over the fluid of the step just taken: the power a.v, |v|^2 and |a|^2 (the largest |a| is the
/// step's own StepReduction).
struct FireSums {
  double power = 0.0;
  double speed2 = 0.0;
  double accel2 = 0.0;
};

struct FireSumsOp {
  FluidView fluid;
  SPHXR_HD FireSums operator()(int i) const {
    const Vec4 v = fluid.velocity[i];
    const Vec4 a = fluid.acceleration[i];
    FireSums s;
    s.power = static_cast<double>(v.x * a.x + v.y * a.y + v.z * a.z);
    s.speed2 = static_cast<double>(v.x * v.x + v.y * v.y + v.z * v.z);
    s.accel2 = static_cast<double>(a.x * a.x + a.y * a.y + a.z * a.z);
    return s;
  }
};

struct FireSumsCombine {
  SPHXR_HD FireSums operator()(const FireSums& a, const FireSums& b) const {
    FireSums r;
    r.power = a.power + b.power;
    r.speed2 = a.speed2 + b.speed2;
    r.accel2 = a.accel2 + b.accel2;
    return r;
  }
};

/// v <- keep v + mix a (FIRE's mixing toward the force; keep = mix = 0 stops every particle).
struct FireMixStage {
  FluidView fluid;
  float keep, mix;
  SPHXR_HD void operator()(int i) const {
    Vec4 v = fluid.velocity[i];
    const Vec4 a = fluid.acceleration[i];
    v.x = keep * v.x + mix * a.x;
    v.y = keep * v.y + mix * a.y;
    v.z = keep * v.z + mix * a.z;
    fluid.velocity[i] = v;
  }
};

// ---- step statistics (a reduction over particles) ------------------------------------------------
struct StepReduction {
  float maxSpeed2 = 0.0f;
  float maxAccel2 = 0.0f;
  float maxDensityError = 0.0f;
  double sumCompression = 0.0;
  int32_t clamped = 0;
  int32_t clampedAt[kClampSites] = {};  // the same per tank face and obstacle (ClampSiteOf)
  int32_t computed = 0;  // particles that computed density and forces this step (set by the backend)
  int32_t pushed = 0;    // fluid particles pushed out of a moving body this step (body_stages.h)
  int32_t nonFinite = 0; // fluid particles with a NaN or infinite position, velocity, acceleration or density
  // DFSPH (set by the backend): iterations of each solve and the mean errors they reached (fractions).
  int32_t densityIterations = 0;
  int32_t divergenceIterations = 0;
  float densityError = 0.0f;
  float divergenceError = 0.0f;
};

struct StepReductionOp {
  FluidView fluid;
  Physics ph;
  SPHXR_HD StepReduction operator()(int i) const {
    const float invRestDensity = ph.invRestDensity;
    StepReduction r;
    const Vec4 v = fluid.velocity[i];
    const Vec4 a = fluid.acceleration[i];
    const Vec4 x = fluid.position[i];
    // (The maxima below drop NaN, as fmaxf(x, NaN) = x does: without this count a NaN particle would never show.)
    const bool finite = Finite(Xyz(x)) && Finite(Xyz(v)) && Finite(Xyz(a)) && IsFinite(fluid.density[i]);
    r.nonFinite = finite ? 0 : 1;
    r.maxSpeed2 = v.x * v.x + v.y * v.y + v.z * v.z;
    r.maxAccel2 = a.x * a.x + a.y * a.y + a.z * a.z;
    const float err = fluid.density[i] * invRestDensity - 1.0f;
    r.maxDensityError = fabsf(err);
    r.sumCompression = err > 0.0f ? err : 0.0f;
    r.clamped = WasClamped(a.w) ? 1 : 0;
    if (r.clamped) {
      const int site = ClampSiteOf(ph, Xyz(x));
      if (site >= 0) r.clampedAt[site] = 1;
    }
    r.pushed = WasPushed(a.w) ? 1 : 0;
    return r;
  }
};

struct StepReductionCombine {
  SPHXR_HD StepReduction operator()(const StepReduction& a, const StepReduction& b) const {
    StepReduction r;
    r.maxSpeed2 = MaxDroppingNaN(a.maxSpeed2, b.maxSpeed2);
    r.maxAccel2 = MaxDroppingNaN(a.maxAccel2, b.maxAccel2);
    r.maxDensityError = MaxDroppingNaN(a.maxDensityError, b.maxDensityError);
    r.sumCompression = a.sumCompression + b.sumCompression;
    r.clamped = a.clamped + b.clamped;
    for (int s = 0; s < kClampSites; ++s) r.clampedAt[s] = a.clampedAt[s] + b.clampedAt[s];
    r.pushed = a.pushed + b.pushed;
    r.nonFinite = a.nonFinite + b.nonFinite;
    return r;
  }
};

}  // namespace sphxr::sim
