// DFSPH's rules (dfsph_rules.h) and constants (dfsph_constants.h).
#include "solvers/dfsph/dfsph_rules.h"

#include <algorithm>

#include "solvers/dfsph/dfsph_constants.h"
#include "solvers/shared_rules.h"

namespace sphxr::sim {

DfsphConstants MakeDfsphConstants(const SceneSetup& scene, const Physics& /*physics*/) {
  const SolverParams& p = scene.params;
  DfsphConstants c;
  c.densityTolerance = 0.01f * p.densityTolerance;  // % to a fraction
  c.divergenceTolerance = 0.01f * p.divergenceTolerance;
  c.minIterations = static_cast<int>(p.minIterations);
  c.maxIterations = static_cast<int>(p.maxIterations);
  c.minDivergenceIterations = static_cast<int>(p.minDivergenceIterations);
  c.maxDivergenceIterations = static_cast<int>(p.maxDivergenceIterations);
  return c;
}

float DfsphStableDt(const StableDtInput& in) {
  const SolverParams& p = in.scene.params;
  float dt = p.maxDt;
  if (in.maxSpeed > 0.0f) dt = std::min(dt, p.cfl * SmoothingOf(p) / in.maxSpeed);
  return std::min(dt, ViscosityDt(in.scene));
}

int64_t DfsphBytes(int64_t slots) { return 12 * ((slots + 15) / 16 * 16) + 16 + 20 + 16 + 8; }

}  // namespace sphxr::sim
