#pragma once
// The stages of divergence-free SPH (Bender & Koschier, "Divergence-free smoothed particle
// hydrodynamics", SCA 2015; "Divergence-free SPH for incompressible and highly viscous fluids", TVCG 2017
// [BK17]), host+device functors for both backends; their order is DfsphSolver::Step (solvers/dfsph/dfsph.h).
//
//   factor       G_ij = V grad W_ij for every neighbour slot (cached: positions do not move until the
//                drift), the boundary terms gB_i = sum_b V_b grad W_ib and sB_i = sum_b V_b v_b . grad W_ib,
//                and alpha_i = 1 / ((sum_j G_ij + gB_i) . (sum_j G_ij + 2 gB_i) + sum_j |G_ij|^2), in the
//                density-ratio form (rho^ = rho / rho0)                                  [BK17 eq. 11]
//   divergence   Jacobi iterations on D rho^_i/Dt = sum_j (v_i - v_j) . G_ij + v_i . gB_i - sB_i until its
//                mean over the fluid, times dt, is below divergence_tolerance    [BK17 §4.2, alg. 2]
//   density      Jacobi iterations on rho^*_i = rho^_i + dt D rho^_i/Dt until the mean compression
//                max(0, rho^* - 1) is below density_tolerance                    [BK17 §4.1, alg. 3]
//   finish       pressure p_i = rho_i^2 (kappa_i + kappa^v_i) / rho0 for probes, haptics and the
//                paddles' reaction; acceleration = (v - v*) / dt + a; the drift
//
// Each iteration is two passes: Predict (the residual of every particle and its stiffness increment
// delta_i) and Correct (v_i -= c (sum_j (delta_i + delta_j) G_ij + 2 delta_i gB_i), c = 1/dt for the
// density solve, 1 for the divergence solve; kappa_i += delta_i). As in the paper the residuals are
// clamped at 0, so every increment pushes and the Jacobi iteration cannot oscillate.
// Boundary particles (walls and paddles, Akinci et al. 2012) mirror the fluid particle's stiffness,
// kappa_b = kappa_i, as the WCSPH walls mirror its pressure: the pair term is 2 kappa_i, and alpha_i's
// diagonal follows it. The paddles enter the divergence through their velocities (sB_i). The solves
// start from zero stiffness each step (no warm start; docs/design/dfsph.md says why).

#include <cstdint>

#include "stages.h"

namespace sphxr::sim {

/// The solve's per-particle arrays (scratch of one step, rebuilt after every sort).
struct DfsphView {
  float* kappa;           // the density solve's stiffness so far, times dt^2
  float* kappaV;          // the divergence solve's, times dt
  Vec3* grad;             // [i * maxNeighbours + k]: G_ij of neighbour slot k of the NeighbourList
  Vec4* boundary;         // xyz gB_i, w sB_i
  float* factor;          // alpha_i
  int32_t* neighbours;    // fluid and boundary particles within the support
  float* delta;           // this iteration's stiffness increment
  uint64_t* error;        // this iteration's residual of each particle, fixed point (ErrorToFixed)
  Vec4* velocityStart;    // v* (after the non-pressure forces), for the step's acceleration
  // The CPU's SIMD passes (dfsph_simd.h) keep G_ij here, lane-blocked (PairCacheStride floats a
  // particle), in place of `grad`; nullptr on the backends that run the scalar stages.
  float* pairGrad = nullptr;
  int pairStride = 0;
};

/// Residuals are summed as integers: the mean error, and so the iteration count, is then the same for
/// any thread count and any summation order (a float sum over threads is not).
inline constexpr double kErrorScale = 4294967296.0;  // 2^32: n < 2^29 particles of residual < 1 fit in 64 bits
SPHXR_HD SPHXR_INLINE uint64_t ErrorToFixed(float e) {
  const float clamped = e > 0.0f ? (e < 1.0f ? e : 1.0f) : 0.0f;
  return static_cast<uint64_t>(static_cast<double>(clamped) * kErrorScale);
}

/// Fewer fluid and boundary neighbours than this: a particle of a thin sheet or spray, whose divergence
/// the kernel sum underestimates; the divergence solve leaves it alone (SPlisHSPlasH's rule in 3D).
inline constexpr int32_t kDfsphMinNeighbours = 20;

/// f(j, G_ij) for every fluid neighbour j of i: the cached gradients, or for a particle whose list
/// overflowed (count > maxNeighbours, NeighbourList) a scan of the 27 cells.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachGradient(const GridView& grid, const FluidView& fluid, const NeighbourList& list,
                                           const Vec3* grad, const Physics& ph, int i, F&& f) {
  const uint32_t found = list.count[i];
  const size_t base = static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
  if (found <= static_cast<uint32_t>(list.maxNeighbours)) {
    const uint32_t* slots = list.index + base;
    for (uint32_t n = 0; n < found; ++n) f(slots[n], grad[base + n]);
    return;
  }
  const CubicSpline k = ph.kernel;
  const float volume = ph.volume;
  const uint32_t self = static_cast<uint32_t>(i);
  ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, Xyz(fluid.position[i]), [&](uint32_t j, Vec3 d) {
    const float r2 = Dot(d, d);
    if (j == self || r2 >= k.H2) return;
    f(j, d * (volume * k.GradFactor(sqrtf(r2))));
  });
}

// ---- 2. factor, kernel-gradient cache and boundary terms ---------------------------------------------
struct DfsphFactorStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  DfsphView view;
  SPHXR_HD void operator()(int i) const {
    const Vec3 xi = Xyz(fluid.position[i]);
    const CubicSpline k = ph.kernel;
    const float volume = ph.volume;
    const uint32_t found = list.count[i];
    const size_t base = static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
    Vec3 sum{0.0f, 0.0f, 0.0f};
    float sum2 = 0.0f;
    if (found <= static_cast<uint32_t>(list.maxNeighbours)) {
      const uint32_t* slots = list.index + base;
      for (uint32_t n = 0; n < found; ++n) {
        const Vec4 pj = fluid.position[slots[n]];
        const Vec3 d{xi.x - pj.x, xi.y - pj.y, xi.z - pj.z};
        const Vec3 g = d * (volume * k.GradFactor(sqrtf(Dot(d, d))));
        view.grad[base + n] = g;
        sum += g;
        sum2 += Dot(g, g);
      }
    } else {
      ForEachGradient(grid, fluid, list, view.grad, ph, i, [&](uint32_t, Vec3 g) {
        sum += g;
        sum2 += Dot(g, g);
      });
    }
    Vec3 gB{0.0f, 0.0f, 0.0f};
    int32_t walls = 0;
    if (fluid.position[i].w != 0.0f) {  // a wall or a paddle within the support (DensityStage's flag)
      int cx, cy, cz;
      grid.CellOf(xi, &cx, &cy, &cz);
      if (grid.boundaryNear[grid.Linear(cx, cy, cz)]) {
        const float invRho0 = ph.invRestDensity;
        ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, grid.boundary, xi, [&](uint32_t b, Vec3 d) {
          const float r2 = Dot(d, d);
          if (r2 >= k.H2) return;
          gB += d * (grid.boundary[b].w * invRho0 * k.GradFactor(sqrtf(r2)));
          ++walls;
        });
      }
    }
    Store(i, xi, sum, sum2, gB, static_cast<int32_t>(found) + walls);
  }

  /// The paddles' terms (their particles move: sB_i), then alpha_i, the boundary terms and the neighbour
  /// count from the fluid's sums (sum_j G_ij, sum_j |G_ij|^2) and the walls' gB_i.
  SPHXR_HD void Store(int i, Vec3 xi, Vec3 sum, float sum2, Vec3 gB, int32_t neighbours) const {
    float sB = 0.0f;
    if (fluid.position[i].w != 0.0f && grid.MovingNear(xi)) {
      const CubicSpline k = ph.kernel;
      const float invRho0 = ph.invRestDensity;
      ForEachInCells(grid, grid.bodyStart, grid.bodyEnd, grid.body, xi, [&](uint32_t b, Vec3 d) {
        const float r2 = Dot(d, d);
        if (r2 >= k.H2) return;
        const Vec3 g = d * (grid.body[b].w * invRho0 * k.GradFactor(sqrtf(r2)));
        gB += g;
        sB += Dot(Xyz(grid.bodyVelocity[b]), g);
        ++neighbours;
      });
    }
    const Vec3 g = sum + gB;
    const float denominator = Dot(g, sum + gB * 2.0f) + sum2;  // the walls mirror kappa_i (see the top)
    view.factor[i] = denominator > 0.0f ? 1.0f / denominator : 0.0f;
    view.boundary[i] = MakeVec4(gB, sB);
    view.neighbours[i] = neighbours;
  }
};

// ---- the iterations: Predict and Correct ---------------------------------------------------------------
/// The rate of change of rho^_i under the current velocities, D rho^_i / Dt (BK17 eq. 4 with the
/// boundary's velocities).
SPHXR_HD SPHXR_INLINE float DensityRate(const GridView& grid, const FluidView& fluid, const NeighbourList& list,
                                        const Physics& ph, const DfsphView& view, int i) {
  const Vec3 vi = Xyz(fluid.velocity[i]);
  float rate = 0.0f;
  ForEachGradient(grid, fluid, list, view.grad, ph, i, [&](uint32_t j, Vec3 g) {
    const Vec4 vj = fluid.velocity[j];
    rate += (vi.x - vj.x) * g.x + (vi.y - vj.y) * g.y + (vi.z - vj.z) * g.z;
  });
  const Vec4 b = view.boundary[i];
  return rate + Dot(vi, Xyz(b)) - b.w;
}

/// Each particle's residual and its stiffness increment. Density solve: r_i = rho^*_i - 1 with rho^*_i
/// = rho^_i + dt D rho^_i/Dt (BK17 eq. 12); divergence solve: r_i = D rho^_i/Dt (eq. 9), 0 for a
/// particle with fewer than kDfsphMinNeighbours neighbours; both clamped at 0 (the water is pushed apart,
/// never pulled together). delta_i = r_i alpha_i in the stored scaling; the error is r_i (times dt for
/// the divergence).
struct DfsphPredictStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  DfsphView view;
  float dt;
  bool density;  // the density solve, else the divergence solve
  SPHXR_HD void operator()(int i) const { Store(i, DensityRate(grid, fluid, list, ph, view, i)); }

  /// The residual and increment from D rho^_i / Dt.
  SPHXR_HD void Store(int i, float rate) const {
    float residual, error;
    if (density) {
      residual = AtLeast(fluid.density[i] * ph.invRestDensity + dt * rate - 1.0f, 0.0f);
      error = residual;
    } else {
      residual = view.neighbours[i] < kDfsphMinNeighbours ? 0.0f : AtLeast(rate, 0.0f);
      error = residual * dt;
    }
    view.delta[i] = residual * view.factor[i];
    view.error[i] = ErrorToFixed(error);
  }
};

/// v_i -= c (sum_j (delta_i + delta_j) G_ij + 2 delta_i gB_i); kappa_i += delta_i (BK17 eq. 10 and 12 in
/// the stored scaling: c = 1/dt for the density solve, 1 for the divergence solve).
struct DfsphCorrectStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  DfsphView view;
  float scale;   // c
  bool density;  // commits to kappa, else to kappaV
  SPHXR_HD void operator()(int i) const {
    const float di = view.delta[i];
    Vec3 dv = Xyz(view.boundary[i]) * (2.0f * di);
    ForEachGradient(grid, fluid, list, view.grad, ph, i, [&](uint32_t j, Vec3 g) { dv += g * (di + view.delta[j]); });
    Store(i, dv);
  }

  /// v_i -= c dv, kappa_i += delta_i.
  SPHXR_HD void Store(int i, Vec3 dv) const {
    const float di = view.delta[i];
    Vec4 v = fluid.velocity[i];
    v.x -= scale * dv.x;
    v.y -= scale * dv.y;
    v.z -= scale * dv.z;
    fluid.velocity[i] = v;
    (density ? view.kappa : view.kappaV)[i] += di;
  }
};

// ---- 4. the non-pressure forces' kick -------------------------------------------------------------------
/// Before the force stage: every pressure zero, so that ForceStage gives viscosity and gravity only.
struct DfsphZeroPressureStage {
  FluidView fluid;
  SPHXR_HD void operator()(int i) const {
    fluid.pressure[i] = 0.0f;
    fluid.pressureTerm[i] = 0.0f;
  }
};

/// After it: v* = v + dt a (kept for the step's acceleration).
struct DfsphKickStage {
  FluidView fluid;
  DfsphView view;
  float dt;
  SPHXR_HD void operator()(int i) const {
    const Vec4 a = fluid.acceleration[i];
    Vec4 v = fluid.velocity[i];
    v.x += dt * a.x;
    v.y += dt * a.y;
    v.z += dt * a.z;
    fluid.velocity[i] = v;
    view.velocityStart[i] = v;
  }
};

// ---- 6. pressure, acceleration, drift ----------------------------------------------------------------------
struct DfsphFinishStage {
  FluidView fluid;
  Physics ph;
  DfsphView view;
  float dt;
  float* bodyPressureTerm;  // per particle, for BodyReactionStage (nullptr without bodies)
  bool drift;  // false: store v and a only; the probes read this state and DriftStage drifts after them
  SPHXR_HD void operator()(int i) const {
    // The physical stiffnesses of this step: kappa / dt^2 and kappa^v / dt. Their velocity change is the
    // one a pressure p_i = rho_i^2 kappa_i / rho0 gives in the WCSPH momentum equation (m p_i / rho_i^2 =
    // V kappa_i), so the probes, the haptics and the paddles' reaction read the same pressure field.
    const float kappa = view.kappa[i] / (dt * dt) + view.kappaV[i] / dt;
    const float term = kappa * ph.invRestDensity;  // p_i / rho_i^2
    const float rho = fluid.density[i];
    fluid.pressure[i] = term * rho * rho;
    fluid.pressureTerm[i] = term;
    if (bodyPressureTerm) bodyPressureTerm[i] = term;
    Vec4 v = fluid.velocity[i];
    const Vec4 v0 = view.velocityStart[i];
    Vec4 a = fluid.acceleration[i];
    const float inv = 1.0f / dt;
    a.x += (v.x - v0.x) * inv;
    a.y += (v.y - v0.y) * inv;
    a.z += (v.z - v0.z) * inv;
    if (drift) {
      DriftAndStore(fluid, ph, dt, i, fluid.position[i], v, a);
    } else {
      fluid.acceleration[i] = a;
    }
  }
};

// ---- a solve's loop on the device --------------------------------------------------------------------
/// Where a solve stands, kept on the device between its iterations: the last residual's integer sum
/// (written by the launch layer's SumInto), the mean error it is, the corrections taken, and whether
/// the solve has ended. The host reads it only every few iterations (DfsphSolver::Solve).
struct DfsphSolveState {
  uint64_t sum;
  float error;
  int32_t iterations;
  int32_t done;
};

/// Clears a solve's state (one item).
struct DfsphSolveResetStage {
  DfsphSolveState* state;
  SPHXR_HD void operator()(int) const { *state = DfsphSolveState{0, 0.0f, 0, 0}; }
};

/// After a prediction's residual sum: the mean error, and whether the solve ends here (below the
/// tolerance after at least the minimum iterations, or at the maximum); else one more correction is
/// counted, the one that follows (one item).
struct DfsphSolveDecideStage {
  DfsphSolveState* state;
  int n;
  float tolerance;
  int minIterations, maxIterations;
  SPHXR_HD void operator()(int) const {
    DfsphSolveState& s = *state;
    if (s.done) return;
    s.error = n > 0 ? static_cast<float>(static_cast<double>(s.sum) / kErrorScale / n) : 0.0f;
    if ((s.error <= tolerance && s.iterations >= minIterations) || s.iterations >= maxIterations) {
      s.done = 1;
    } else {
      ++s.iterations;
    }
  }
};

/// A solve's pass that does nothing once the solve has ended: the iterations launched after the end
/// (between two of the host's reads of the state) cost a launch each and change nothing.
template <class F>
struct UntilSolved {
  const DfsphSolveState* state;
  F stage;
  SPHXR_HD void operator()(int i) const {
    if (!state->done) stage(i);
  }
};

}  // namespace sphxr::sim
