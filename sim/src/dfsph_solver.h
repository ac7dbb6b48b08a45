#pragma once
// Divergence-free SPH (Bender & Koschier, "Divergence-free smoothed particle hydrodynamics", SCA 2015;
// "Divergence-free SPH for incompressible and highly viscous fluids", TVCG 2017 [BK17]): the pressure
// solver whose step follows the flow speed instead of the sound speed. One source for both backends:
// the stages are host+device functors, DfsphSolver<Traits> launches them (backend_impl.h calls it).
//
// The step, after the shared cells, sort, grid and moving bodies (backend_impl.h):
//   1. density      rho_i = sum_j m W_ij + sum_b Psi_b W_ib and the neighbour lists (DensityStage,
//                   the same stage as WCSPH's; its Tait pressure is not used)            [BK17 eq. 1]
//   2. factor       G_ij = V grad W_ij for every neighbour slot (cached: positions do not move
//                   until the drift), the boundary terms gB_i = sum_b V_b grad W_ib and
//                   sB_i = sum_b V_b v_b . grad W_ib, and alpha_i = 1 / ((sum_j G_ij + gB_i) .
//                   (sum_j G_ij + 2 gB_i) + sum_j |G_ij|^2) (walls mirrored, below), in the
//                   density-ratio form (rho^ = rho / rho0)                               [BK17 eq. 11]
//   3. divergence   Jacobi iterations on D rho^_i/Dt = sum_j (v_i - v_j) . G_ij +
//                   v_i . gB_i - sB_i until its mean over the fluid, times dt, is below
//                   divergence_tolerance                                         [BK17 §4.2, alg. 2]
//   4. forces       viscosity and gravity: the WCSPH force stage with every pressure zero, v* = v + dt a
//   5. density      Jacobi iterations on rho^*_i = rho^_i + dt D rho^_i/Dt until the mean
//                   compression max(0, rho^* - 1) is below density_tolerance       [BK17 §4.1, alg. 3]
//   6. finish       pressure p_i = rho_i^2 (kappa_i + kappa^v_i) / rho0 for probes, haptics and the
//                   paddles' reaction; acceleration = (v - v*) / dt + a; drift x += dt v, domain clamp
//
// Each iteration is two passes: Predict (the residual of every particle and its stiffness increment
// delta_i) and Correct (v_i -= c (sum_j (delta_i + delta_j) G_ij + 2 delta_i gB_i), c = 1/dt for the
// density solve, 1 for the divergence solve; kappa_i += delta_i). As in the paper the residuals are
// clamped at 0, so every increment pushes: the Jacobi iteration then cannot oscillate (a projected form
// that let increments take pressure back diverged on the rest lattice, whose checkerboard mode an
// undamped Jacobi step overshoots).
// Boundary particles (walls and paddles, Akinci et al. 2012) mirror the fluid particle's stiffness,
// kappa_b = kappa_i, as the WCSPH walls mirror its pressure: the pair term is kappa_i + kappa_b =
// 2 kappa_i, and alpha_i's diagonal follows it, (sum_j G_ij + gB_i) . (sum_j G_ij + 2 gB_i) +
// sum_j |G_ij|^2. With kappa_i alone (SPlisHSPlasH's form) a flat wall gives half the push of the fluid
// it replaces, and the first layer slid into the walls at rest density: still water put 12 % of its
// particles on the domain clamp every step, and its pressure came out 7-12 % above hydrostatic.
// The paddles enter the divergence through their velocities (sB_i).
// There is no warm start: the clamped increments cannot take back a stiffness that a warm start
// over-applies, so it ratchets up (still water after 1 s: pressure 2.3-4.2x hydrostatic and 4 cm/s of
// motion starting from the last step's stiffness, 0.8-1.6x with half of it, within 1.12x without).
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/memory.h>
#include <thrust/reduce.h>

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
    int32_t neighbours = static_cast<int32_t>(found);
    Vec3 gB{0.0f, 0.0f, 0.0f};
    float sB = 0.0f;
    if (fluid.position[i].w != 0.0f) {  // a wall or a paddle within the support (DensityStage's flag)
      const float invRho0 = ph.invRestDensity;
      int cx, cy, cz;
      grid.CellOf(xi, &cx, &cy, &cz);
      if (grid.boundaryNear[grid.Linear(cx, cy, cz)]) {
        ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, grid.boundary, xi, [&](uint32_t b, Vec3 d) {
          const float r2 = Dot(d, d);
          if (r2 >= k.H2) return;
          gB += d * (grid.boundary[b].w * invRho0 * k.GradFactor(sqrtf(r2)));
          ++neighbours;
        });
      }
      if (grid.MovingNear(xi)) {
        ForEachInCells(grid, grid.bodyStart, grid.bodyEnd, grid.body, xi, [&](uint32_t b, Vec3 d) {
          const float r2 = Dot(d, d);
          if (r2 >= k.H2) return;
          const Vec3 g = d * (grid.body[b].w * invRho0 * k.GradFactor(sqrtf(r2)));
          gB += g;
          sB += Dot(Xyz(grid.bodyVelocity[b]), g);
          ++neighbours;
        });
      }
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
  SPHXR_HD void operator()(int i) const {
    const float rate = DensityRate(grid, fluid, list, ph, view, i);
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

/// Launches the DFSPH stages on a backend's system (Traits as in backend_impl.h) and owns their arrays.
template <class Traits>
class DfsphSolver {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  /// What one solve reached.
  struct Result {
    int iterations = 0;
    float error = 0.0f;  // mean residual (fraction) after the last correction
  };

  /// Sizes the arrays for n particles and computes the factor and boundary terms (after the density stage).
  void Prepare(const GridView& grid, const FluidView& fluid, const NeighbourList& list, const Physics& ph) {
    const size_t n = static_cast<size_t>(fluid.count);
    const size_t slots = n * static_cast<size_t>(list.maxNeighbours);
    if (m_grad.size() != slots) m_grad.resize(slots);
    if (m_boundary.size() != n) {
      m_boundary.resize(n);
      m_factor.resize(n);
      m_neighbours.resize(n);
      m_delta.resize(n);
      m_error.resize(n);
      m_velocityStart.resize(n);
      m_kappa.resize(n);
      m_kappaV.resize(n);
    }
    ForEach(fluid.count, DfsphFactorStage{grid, fluid, list, ph, View()});
  }

  /// The divergence-free solve (BK17 alg. 2), on the velocities at the start of the step.
  Result Divergence(const GridView& grid, const FluidView& fluid, const NeighbourList& list, const Physics& ph, float dt) {
    if (ph.maxDivergenceIterations <= 0) return {};
    return Solve(grid, fluid, list, ph, dt, false, 0, ph.maxDivergenceIterations, ph.divergenceTolerance);
  }

  /// v* = v + dt a after the force stage.
  void Kick(const FluidView& fluid, float dt) { ForEach(fluid.count, DfsphKickStage{fluid, View(), dt}); }

  /// The density-invariance solve (BK17 alg. 3), on v*.
  Result Density(const GridView& grid, const FluidView& fluid, const NeighbourList& list, const Physics& ph, float dt) {
    return Solve(grid, fluid, list, ph, dt, true, ph.minIterations, ph.maxIterations, ph.densityTolerance);
  }

  /// Pressure, acceleration and (with `drift`) the drift; without it DriftStage drifts later.
  void Finish(const FluidView& fluid, const Physics& ph, float dt, float* bodyPressureTerm, bool drift) {
    ForEach(fluid.count, DfsphFinishStage{fluid, ph, View(), dt, bodyPressureTerm, drift});
  }

  void ZeroPressure(const FluidView& fluid) { ForEach(fluid.count, DfsphZeroPressureStage{fluid}); }

 private:
  Result Solve(const GridView& grid, const FluidView& fluid, const NeighbourList& list, const Physics& ph, float dt,
               bool density, int minIterations, int maxIterations, float tolerance) {
    const int n = fluid.count;
    const DfsphView view = View();
    const float scale = density ? 1.0f / dt : 1.0f;
    auto& kappa = density ? m_kappa : m_kappaV;
    thrust::fill(Traits::Policy(), kappa.begin(), kappa.end(), 0.0f);
    Result result;
    for (;;) {
      ForEach(n, DfsphPredictStage{grid, fluid, list, ph, view, dt, density});
      const uint64_t sum = thrust::reduce(Traits::Policy(), m_error.begin(), m_error.end(), uint64_t{0});
      result.error = n > 0 ? static_cast<float>(static_cast<double>(sum) / kErrorScale / n) : 0.0f;
      if ((result.error <= tolerance && result.iterations >= minIterations) || result.iterations >= maxIterations) break;
      ForEach(n, DfsphCorrectStage{grid, fluid, list, ph, view, scale, density});
      ++result.iterations;
    }
    return result;
  }

  template <class F>
  void ForEach(int n, const F& f) {
    if constexpr (Traits::kSimdStages) {  // the CPU: guided chunks (backend_cpu.cpp)
      Traits::ForEachGuided(n, 64, f);
    } else {
      thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), n, f);
    }
  }

  DfsphView View() {
    auto raw = [](auto& v) { return thrust::raw_pointer_cast(v.data()); };
    return DfsphView{raw(m_kappa), raw(m_kappaV), raw(m_grad), raw(m_boundary), raw(m_factor), raw(m_neighbours), raw(m_delta), raw(m_error),
                     raw(m_velocityStart)};
  }

  Vector<Vec3> m_grad;
  Vector<Vec4> m_boundary;
  Vector<float> m_factor;
  Vector<int32_t> m_neighbours;
  Vector<float> m_delta;
  Vector<uint64_t> m_error;
  Vector<Vec4> m_velocityStart;
  Vector<float> m_kappa, m_kappaV;
};

}  // namespace sphxr::sim
