// WCSPH's rules (wcsph_rules.h).
#include "solvers/wcsph/wcsph_rules.h"

#include <algorithm>
#include <cmath>

#include "solvers/shared_rules.h"

namespace sphxr::sim {

float WcsphStableDt(const StableDtInput& in) {
  const SolverParams& p = in.scene.params;
  const float h = SmoothingOf(p);
  float dt = std::min(p.maxDt, p.cfl * h / (SoundSpeedOf(p) + in.maxSpeed));
  if (in.maxAccel > 0.0f) dt = std::min(dt, 0.25f * std::sqrt(h / in.maxAccel));
  return std::min(dt, ViscosityDt(in.scene));
}

int64_t WcsphBytes(int64_t) { return 0; }

}  // namespace sphxr::sim
