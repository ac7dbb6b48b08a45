#pragma once
// The stages of position-based fluids (Macklin & Müller, "Position Based Fluids", ACM TOG 32(4), 2013
// [MM13]), host+device functors for both backends; their order is PbfSolver::Step (solvers/pbf/pbf.h).
//
//   predict   v* = v + dt g (capped at pbf_max_speed), x* = x + dt v*; the step's start position x
//             is kept in acceleration.xyz until the finish (the field list sorts it with the particle)
//   lambda    rho_i = sum_j m W_ij + sum_b Psi_b W_ib at x*, C_i = max(rho_i / rho0 - 1, 0) and
//             lambda_i = -C_i / (sum_k |grad_k C_i|^2 + eps)                   [MM13 eq. 1, 9, 11]
//             with grad_j C_i = -V grad W_ij, grad_i C_i = V sum_j grad W_ij + sum_b (Psi_b / rho0) grad W_ib
//             (the walls and paddles are Akinci et al. 2012's boundary particles, as everywhere)
//   correct   dx_i = sum_j V (lambda_i + lambda_j + s_corr) grad W_ij + lambda_i B_i,
//             B_i = sum_b (Psi_b / rho0) grad W_ib kept from the lambda pass (the positions have not moved),
//             s_corr = -k (W_ij / W(dq))^n against clumping where the kernel is cut  [MM13 eq. 12, 13]
//   collide   x* out of the tank's faces and the obstacles by the particle's radius (half a spacing),
//             in the prediction and after every iteration's correction                 [MM13 alg. 1]
//   finish    v = (x* - x) / dt (capped at pbf_max_speed), the clamps, the pressure estimate (below)
//   xsph      v_i += c sum_j V (v_j - v_i) W_ij (capped at pbf_max_speed)                [MM13 eq. 17]
//   vorticity (pbf_vorticity > 0) omega_i = sum_j V (v_i - v_j) x grad_i W_ij, N = grad|omega| / |grad|omega||,
//             v_i += dt eps (N x omega_i) (capped at pbf_max_speed)              [MM13 eq. 15-16]
//
// The pressure estimate: a step's corrections move particle i by sum over iterations of its lambda
// terms, the displacement a pressure p_i would give in the WCSPH momentum equation over dt^2 when
// p_i / rho_i^2 = -Lambda_i / (rho0 dt^2), Lambda_i = the sum of lambda_i over the step's iterations.
// In still water the corrections hold each layer against gravity, so the estimate is rho0 g depth
// there; the probes, the haptics and the paddles' reaction read it.
#include "solvers/pbf/pbf_constants.h"
#include "stages.h"

namespace sphxr::sim {

/// The solve's per-particle arrays (scratch of one step).
struct PbfView {
  float* lambda;       // this iteration's lambda_i
  float* lambdaSum;    // Lambda_i, the step's sum
  Vec4* delta;         // this iteration's position correction (xsph: the velocity change)
  Vec4* boundaryGrad;  // B_i = sum_b (Psi_b / rho0) grad W_ib over the walls and paddles, from the lambda
                       // pass: the correction's boundary term is lambda_i B_i (positions do not move between)
  // The CPU's SIMD passes only (solvers/pbf/pbf_simd.h; nullptr on the other backends): the lambda pass keeps
  // V grad W_ij of each list slot, and lambda_i (sum_j V grad W_ij + B_i) + sum_j s_corr V grad W_ij of each
  // particle, so the correction pass adds sum_j lambda_j V grad W_ij without evaluating the kernel again.
  float* pairGrad;     // pairStride floats a particle: per kLanes slots, the x, y and z of kLanes pairs
  Vec4* ownCorrection;
  int pairStride;
};


/// The collision response of MM13's solver loop: x* moved out of the tank's faces and the obstacles to
/// the particle's radius from them (pbf.contact beyond the clamp box, whose inset is a quarter
/// spacing). The walls' boundary particles alone are soft in the constraint: a particle pushed towards
/// a sheet leaves its fluid neighbours behind as it nears the walls' ones, and its density rises by
/// 2.5 % only at the clamp box (docs/design/pbf.md), too little against the corrections of a column
/// above it. Returns whether it moved the particle (the step's clamp count does not include it).
SPHXR_HD SPHXR_INLINE bool PbfCollide(const Physics& ph, const PbfConstants& pbf, Vec4* x) {
  const float g = pbf.contact;
  Vec4 unused{};  // the velocity follows from the positions at the step's end
  const Vec3 lo{ph.domainMin.x + g, ph.domainMin.y + g, ph.domainMin.z + g};
  const Vec3 hi{ph.domainMax.x - g, ph.closedTop ? ph.domainMax.y - g : ph.domainMax.y, ph.domainMax.z - g};
  bool moved = ClampIntoBox(lo, hi, x, &unused);
  for (int k = 0; k < ph.obstacleCount; ++k) {
    const Vec3 olo{ph.obstacleMin[k].x - g, ph.obstacleMin[k].y - g, ph.obstacleMin[k].z - g};
    const Vec3 ohi{ph.obstacleMax[k].x + g, ph.obstacleMax[k].y + g, ph.obstacleMax[k].z + g};
    moved = PushOutOfBox(olo, ohi, x, &unused) || moved;
  }
  return moved;
}

/// |v| at most pbf_max_speed, its direction kept: the safety net after every change of the velocity.
SPHXR_HD SPHXR_INLINE void PbfCapSpeed(const PbfConstants& pbf, Vec4* v) {
  const float speed2 = v->x * v->x + v->y * v->y + v->z * v->z;
  if (speed2 > pbf.maxSpeed * pbf.maxSpeed) {
    const float s = pbf.maxSpeed / sqrtf(speed2);
    v->x *= s, v->y *= s, v->z *= s;
  }
}

/// x* = x + dt (v + dt g) and its collision response, the start position in acceleration.xyz.
/// Before the grid: where the grid is rebuilt, it is built at the predicted positions. With a skin
/// (`reference`: every particle where the lists were built), a particle that is now more than half the
/// margin from there sets `rebuild` (PressureSolver::GridGate): a race of equal writes, no reduction.
struct PbfPredictStage {
  FluidView fluid;
  Physics ph;
  PbfConstants pbf;
  float dt;
  const Vec4* reference = nullptr;
  int* rebuild = nullptr;
  SPHXR_HD void operator()(int i) const {
    Vec4 x = fluid.position[i];
    Vec4 v = fluid.velocity[i];
    v.x += dt * ph.gravity.x;
    v.y += dt * ph.gravity.y;
    v.z += dt * ph.gravity.z;
    PbfCapSpeed(pbf, &v);
    fluid.acceleration[i] = Vec4{x.x, x.y, x.z, 0.0f};
    x.x += dt * v.x;
    x.y += dt * v.y;
    x.z += dt * v.z;
    PbfCollide(ph, pbf, &x);
    fluid.position[i] = x;
    fluid.velocity[i] = v;
    if (reference) {
      const Vec3 moved = Xyz(x) - Xyz(reference[i]);
      if (Dot(moved, moved) > pbf.halfMargin2) *rebuild = 1;
    }
  }
};

/// Where the gate is open (the lists were just built): every particle's position, the reference of
/// PbfPredictStage's check; then the gate's own reset.
struct PbfReferenceStage {
  FluidView fluid;
  Vec4* reference;
  const int* gate;
  SPHXR_HD void operator()(int i) const {
    if (*gate == 0) return;
    reference[i] = fluid.position[i];
  }
};

/// Particle i's neighbours within the support at x*, from its skin list (the pairs within the support
/// plus the margin when the lists were built; in that list's order). A skin list that overflowed makes
/// this one overflow too, so that the passes scan the cells (whose size is the support plus the
/// margin: a stale cell still holds every particle within the support of any point).
struct PbfNearListStage {
  FluidView fluid;
  NeighbourList skin;
  NeighbourList list;
  float h2;
  SPHXR_HD void operator()(int i) const {
    const uint32_t capacity = static_cast<uint32_t>(list.maxNeighbours);
    const uint32_t found = skin.count[i];
    if (found > static_cast<uint32_t>(skin.maxNeighbours)) {
      list.count[i] = capacity + 1u;
      return;
    }
    const Vec3 xi = Xyz(fluid.position[i]);
    const uint32_t* in = skin.index + static_cast<size_t>(i) * static_cast<size_t>(skin.maxNeighbours);
    uint32_t* out = list.index + static_cast<size_t>(i) * static_cast<size_t>(list.maxNeighbours);
    uint32_t near = 0;
    for (uint32_t k = 0; k < found; ++k) {
      const uint32_t j = in[k];
      const Vec4 pj = fluid.position[j];
      const Vec3 d{xi.x - pj.x, xi.y - pj.y, xi.z - pj.z};
      if (Dot(d, d) < h2) {
        if (near < capacity) out[near] = j;
        ++near;
      }
    }
    list.count[i] = near;
  }
};

/// f(Psi_b, x_i - x_b) for every paddle particle within the support of xi.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachBodyNear(const GridView& grid, Vec3 xi, float h2, F&& f) {
  if (!grid.MovingNear(xi)) return;
  ForEachInCells(grid, grid.bodyStart, grid.bodyEnd, grid.body, xi, [&](uint32_t b, Vec3 d) {
    if (Dot(d, d) < h2) f(grid.body[b].w, d);
  });
}

/// f(Psi_b, x_i - x_b) for every wall and paddle particle within the support of xi.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachBoundaryNear(const GridView& grid, Vec3 xi, float h2, F&& f) {
  int cx, cy, cz;
  grid.CellOf(xi, &cx, &cy, &cz);
  if (grid.boundaryNear[grid.Linear(cx, cy, cz)]) {
    ForEachInCells(grid, grid.boundaryStart, grid.boundaryEnd, grid.boundary, xi, [&](uint32_t b, Vec3 d) {
      if (Dot(d, d) < h2) f(grid.boundary[b].w, d);
    });
  }
  ForEachBodyNear(grid, xi, h2, f);
}

/// f(j, x_i - x_j) for every other fluid particle in particle i's list (or cells, where it overflowed).
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachOther(const GridView& grid, const FluidView& fluid, const NeighbourList& list, int i,
                                        Vec3 xi, F&& f) {
  const uint32_t self = static_cast<uint32_t>(i);
  ForEachFluidNeighbour(grid, fluid, list, i, xi, [&](uint32_t j, Vec3 d) {
    if (j != self) f(j, d);
  });
}

/// f(j, x_i - x_j, r) for every other fluid particle in particle i's list within the kernel's support.
template <class F>
SPHXR_HD SPHXR_INLINE void ForEachWithin(const GridView& grid, const FluidView& fluid, const NeighbourList& list, int i,
                                         Vec3 xi, const CubicSpline& k, F&& f) {
  ForEachOther(grid, fluid, list, i, xi, [&](uint32_t j, Vec3 d) {
    const float r2 = Dot(d, d);
    if (r2 < k.H2) f(j, d, sqrtf(r2));
  });
}

struct PbfLambdaStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  PbfConstants pbf;
  PbfView view;
  SPHXR_HD void operator()(int i) const {
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(fluid.position[i]);
    const float volume = ph.volume;
    float sumW = k.W(0.0f);
    float sum2 = 0.0f;
    Vec3 gradI{0.0f, 0.0f, 0.0f};
    ForEachWithin(grid, fluid, list, i, xi, k, [&](uint32_t, Vec3 d, float r) {
      sumW += k.W(r);
      const Vec3 g = d * (volume * k.GradFactor(r));
      gradI += g;
      sum2 += Dot(g, g);
    });
    float sumBoundary = 0.0f;
    const float invRho0 = ph.invRestDensity;
    Vec3 gradB{0.0f, 0.0f, 0.0f};
    ForEachBoundaryNear(grid, xi, k.H2, [&](float psi, Vec3 d) {
      const float r = sqrtf(Dot(d, d));
      sumBoundary += psi * k.W(r);
      gradB += d * (psi * invRho0 * k.GradFactor(r));
    });
    view.boundaryGrad[i] = MakeVec4(gradB);
    gradI += gradB;
    Finish(i, ph.mass * sumW + sumBoundary, sum2 + Dot(gradI, gradI));
  }
  /// rho_i, and lambda_i from it and sum_k |grad_k C_i|^2 (also the CPU's SIMD form's end, solvers/pbf/pbf_simd.h).
  SPHXR_HD SPHXR_INLINE float Finish(int i, float rho, float gradSum2) const {
    fluid.density[i] = rho;
    const float c = AtLeast(rho * ph.invRestDensity - 1.0f, 0.0f);
    const float lambda = -c / (gradSum2 + pbf.relaxation);
    view.lambda[i] = lambda;
    view.lambdaSum[i] += lambda;
    return lambda;
  }
};

/// MM13's artificial pressure s_corr = -k (W(r) / W(dq))^n of a pair at distance r with W(r) = w [eq. 13].
SPHXR_HD SPHXR_INLINE float PbfCorr(const PbfConstants& pbf, float w) {
  if (pbf.corrK <= 0.0f) return 0.0f;
  const float wq = w * pbf.invCorrW;
  float p = wq;
  for (int e = 1; e < pbf.corrN; ++e) p *= wq;
  return -pbf.corrK * p;
}

struct PbfCorrectStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  PbfConstants pbf;
  PbfView view;
  SPHXR_HD void operator()(int i) const {
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(fluid.position[i]);
    const float li = view.lambda[i];
    const float volume = ph.volume;
    Vec3 dx{0.0f, 0.0f, 0.0f};
    ForEachWithin(grid, fluid, list, i, xi, k, [&](uint32_t j, Vec3 d, float r) {
      const float corr = PbfCorr(pbf, k.W(r));
      dx += d * ((li + view.lambda[j] + corr) * volume * k.GradFactor(r));
    });
    dx += Xyz(view.boundaryGrad[i]) * li;  // sum_b lambda_i (Psi_b / rho0) grad W_ib
    view.delta[i] = MakeVec4(dx);
  }
};

/// x* += dx (after every particle's correction is known: Jacobi), then the collision response.
struct PbfApplyStage {
  FluidView fluid;
  Physics ph;
  PbfConstants pbf;
  PbfView view;
  SPHXR_HD void operator()(int i) const {
    Vec4 x = fluid.position[i];
    const Vec4 d = view.delta[i];
    x.x += d.x;
    x.y += d.y;
    x.z += d.z;
    PbfCollide(ph, pbf, &x);
    fluid.position[i] = x;
  }
};

/// v = (x* - x) / dt after the clamps, the acceleration (v - v^n) / dt with its clamp flag, and the
/// pressure estimate (top of the file) into pressure, pressureTerm and the bodies' reaction term.
struct PbfFinishStage {
  FluidView fluid;
  Physics ph;
  PbfConstants pbf;
  PbfView view;
  float dt;
  float* bodyPressureTerm;  // nullptr without bodies
  SPHXR_HD void operator()(int i) const {
    Vec4 x = fluid.position[i];
    const Vec4 start = fluid.acceleration[i];
    const Vec4 vStar = fluid.velocity[i];
    const float inv = 1.0f / dt;
    Vec4 v{(x.x - start.x) * inv, (x.y - start.y) * inv, (x.z - start.z) * inv, vStar.w};
    // The safety net holds for the velocity the corrections give too, not only the predicted one.
    PbfCapSpeed(pbf, &v);
    bool clamped = ph.obstacleCount > 0 && ClampOutOfObstacles(ph, &x, &v);
    clamped = ClampToDomain(ph, &x, &v) || clamped;
    // v* = v^n + dt g: the step's acceleration is (v - v^n) / dt = (v - v*) / dt + g.
    const Vec4 a{(v.x - vStar.x) * inv + ph.gravity.x, (v.y - vStar.y) * inv + ph.gravity.y,
                 (v.z - vStar.z) * inv + ph.gravity.z, clamped ? 1.0f : 0.0f};
    fluid.position[i] = x;
    fluid.velocity[i] = v;
    fluid.acceleration[i] = a;
    const float term = -view.lambdaSum[i] * ph.invRestDensity * inv * inv;  // p_i / rho_i^2
    const float rho = fluid.density[i];
    fluid.pressure[i] = term * rho * rho;
    fluid.pressureTerm[i] = term;
    if (bodyPressureTerm) bodyPressureTerm[i] = term;
  }
};

/// XSPH viscosity [MM13 eq. 17]: the velocity change into view.delta (applied by PbfAddVelocityChangeStage).
struct PbfXsphStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  PbfConstants pbf;
  PbfView view;
  SPHXR_HD void operator()(int i) const {
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(fluid.position[i]);
    const Vec3 vi = Xyz(fluid.velocity[i]);
    Vec3 dv{0.0f, 0.0f, 0.0f};
    ForEachWithin(grid, fluid, list, i, xi, k, [&](uint32_t j, Vec3, float r) {
      dv += (Xyz(fluid.velocity[j]) - vi) * k.W(r);
    });
    view.delta[i] = MakeVec4(dv * (pbf.xsph * ph.volume));
  }
};

/// v_i += view.delta_i, capped: the velocity change a pass before it left there (XSPH's, the
/// confinement's), which can push a particle past the cap the finish held it to.
struct PbfAddVelocityChangeStage {
  FluidView fluid;
  PbfConstants pbf;
  PbfView view;
  SPHXR_HD void operator()(int i) const {
    Vec4 v = fluid.velocity[i];
    const Vec4 d = view.delta[i];
    v.x += d.x;
    v.y += d.y;
    v.z += d.z;
    PbfCapSpeed(pbf, &v);
    fluid.velocity[i] = v;
  }
};

/// Vorticity confinement [MM13 eq. 15-16], its first pass: the velocity's curl omega_i = sum_j V (v_i - v_j)
/// x grad_i W_ij (2 Omega in a rigid rotation), into `vorticity` (w: |omega_i|).
struct PbfVorticityStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  Vec4* vorticity;
  SPHXR_HD void operator()(int i) const {
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(fluid.position[i]);
    const Vec3 vi = Xyz(fluid.velocity[i]);
    Vec3 w{0.0f, 0.0f, 0.0f};
    ForEachWithin(grid, fluid, list, i, xi, k, [&](uint32_t j, Vec3 d, float r) {
      w += Cross(vi - Xyz(fluid.velocity[j]), d * k.GradFactor(r));
    });
    w = w * ph.volume;
    vorticity[i] = MakeVec4(w, Length(w));
  }
};

/// Its second pass: eta_i = grad |omega| = sum_j V (|omega_j| - |omega_i|) grad_i W_ij, N = eta / |eta|
/// (towards the vortex's core), and the velocity change dt eps (N x omega_i) into view.delta (applied
/// by PbfAddVelocityChangeStage); eps is pbf_vorticity (m/s). Where |eta| vanishes (no vortex) nothing changes.
struct PbfConfinementStage {
  GridView grid;
  FluidView fluid;
  NeighbourList list;
  Physics ph;
  PbfConstants pbf;
  PbfView view;
  const Vec4* vorticity;
  float dt;
  SPHXR_HD void operator()(int i) const {
    const CubicSpline k = ph.kernel;
    const Vec3 xi = Xyz(fluid.position[i]);
    const Vec4 wi = vorticity[i];
    Vec3 eta{0.0f, 0.0f, 0.0f};
    ForEachWithin(grid, fluid, list, i, xi, k, [&](uint32_t j, Vec3 d, float r) {
      eta += d * ((vorticity[j].w - wi.w) * k.GradFactor(r));
    });
    // N = eta / |eta|, but proportional to eta where |eta| is under 1e-3 |omega_i| / H (a vorticity
    // that is flat within rounding has no direction to confine toward).
    const float length = AtLeast(Length(eta), 1e-3f * wi.w * k.invH);
    Vec3 dv{0.0f, 0.0f, 0.0f};
    if (length > 0.0f) dv = Cross(eta * (1.0f / length), Xyz(wi)) * (pbf.vorticity * dt);
    view.delta[i] = MakeVec4(dv);
  }
};

/// max(0, rho_i / rho0 - 1): the constraint's residual (the solve's density error).
struct PbfResidual {
  FluidView fluid;
  float invRestDensity;
  SPHXR_HD double operator()(int i) const { return AtLeast(fluid.density[i] * invRestDensity - 1.0f, 0.0f); }
};

}  // namespace sphxr::sim
