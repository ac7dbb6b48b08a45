// What the methods' rules share (shared_rules.h).
#include "solvers/shared_rules.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sphxr::sim {

float SoundSpeedOf(const SolverParams& p) { return std::sqrt(p.exponent * p.stiffness / p.restDensity); }
float SmoothingOf(const SolverParams& p) { return 0.5f * p.spacing * p.supportFactor; }

float ViscosityDt(const SceneSetup& scene) {
  const SolverParams& p = scene.params;
  const TankFriction& f = scene.friction;
  float alpha = std::max(p.viscosity, p.boundaryViscosity);  // the paddles' default alpha too
  for (WallFriction w : {f.floor, f.top, f.xMin, f.xMax, f.zMin, f.zMax, f.obstacles}) {
    alpha = std::max(alpha, WallFrictionAlpha(p, w));
  }
  if (!(alpha > 0.0f)) return std::numeric_limits<float>::infinity();
  return 0.5f * SmoothingOf(p) / (alpha * SoundSpeedOf(p));
}

}  // namespace sphxr::sim
