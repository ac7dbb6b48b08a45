#pragma once
// Stage 6 of a step: symplectic Euler with the impulse hold's kick, the domain clamp, and the step's
// statistics (a reduction over the particles: what the next time step depends on).
#include <cstdint>

#include "stages/clamp.h"
#include "stages/contact.h"
#include "stages/views.h"

namespace sphxr::sim {

/// The end of every integrator: the walls' contact kick (stages/contact.h), x += dt v, the domain and
/// obstacle clamps (flagged in acceleration.w, so that the step reports how many were clamped, and
/// where: StepReductionOp), and the store of particle i's position, velocity and acceleration.
SPHXR_HD SPHXR_INLINE void DriftAndStore(const FluidView& fluid, const Physics& ph, float dt, int i, Vec4 x, Vec4 v,
                                         Vec4 a) {
  if (ph.contactStrength > 0.0f && (!ph.contactBelowRestOnly || fluid.density[i] < ph.restDensity)) {
    WallContact(ph, Xyz(x), dt, &v);
  }
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


// acceleration.w after a step: 1 clamped into the domain (IntegrateStage), 2 pushed out of a moving
// body (PushOutStage, stages/bodies.h), 3 both. StepReductionOp counts them; tests read them too.
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

/// x += dt v and the domain clamp, for an integrator whose velocity and acceleration are already stored
/// (DFSPH's Finish without its drift, while probes read the state before it): DriftAndStore as it would
/// have run there, the same numbers.
struct DriftStage {
  FluidView fluid;
  Physics ph;
  float dt;
  SPHXR_HD void operator()(int i) const {
    DriftAndStore(fluid, ph, dt, i, fluid.position[i], fluid.velocity[i], fluid.acceleration[i]);
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
  int32_t pushed = 0;    // fluid particles pushed out of a moving body this step (stages/bodies.h)
  int32_t nonFinite = 0; // fluid particles with a NaN or infinite position, velocity, acceleration or density
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
