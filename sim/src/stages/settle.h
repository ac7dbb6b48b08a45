#pragma once
// Settling before a run (Solver::Settle, docs/design/settle.md): FIRE's sums and velocity mixing
// (Bitzek et al. 2006) after each of the solver's own steps.

#include "stages/views.h"

namespace sphxr::sim {

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

}  // namespace sphxr::sim
