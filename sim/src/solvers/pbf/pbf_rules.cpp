// PBF's rules (pbf_rules.h) and constants (pbf_constants.h).
#include "solvers/pbf/pbf_rules.h"

#include <algorithm>
#include <cmath>

#include "sampling.h"
#include "solvers/pbf/pbf_constants.h"
#include "sphxr/common/log.h"

namespace sphxr::sim {

PbfConstants MakePbfConstants(const SceneSetup& scene, const Physics& ph) {
  const SolverParams& p = scene.params;
  const float support = p.spacing * p.supportFactor;
  PbfConstants c;
  c.iterations = static_cast<int>(p.pbfIterations);
  // The constraint's scale D0 = sum_k |grad_k C_i|^2 of the rest lattice (1/m^2): epsilon and s_corr are
  // given relative to it, so that they mean the same at every spacing (MM13's 600 and 0.1 are in its own
  // units; s_corr enters beside lambda, whose scale is 1/D0).
  const float d0 = PbfRestGradientSum(ph.kernel, p.spacing, ph.volume);
  c.relaxation = p.pbfRelaxation * d0;
  c.corrK = p.pbfCorrK / d0;
  c.corrN = static_cast<int>(p.pbfCorrN);
  c.invCorrW = 1.0f / ph.kernel.W(p.pbfCorrDq * support);
  c.xsph = p.pbfXsph;
  c.vorticity = p.pbfVorticity;
  // The collision response keeps a particle its radius (half a spacing, where the sampling puts the
  // first layer) from a face: a quarter spacing beyond the clamp box's quarter-spacing inset.
  c.contact = 0.25f * p.spacing;
  c.maxSpeed = p.pbfMaxSpeed;
  c.substeps = static_cast<int>(p.pbfSubsteps);
  c.margin = PbfListMargin(p);
  c.halfMargin2 = 0.25f * c.margin * c.margin;
  c.skinCapacity = NeighbourCapacity(p.supportFactor + p.pbfSkin);
  return c;
}

float PbfListMargin(const SolverParams& params) { return params.pbfSkin * params.spacing; }

float PbfStableDt(const StableDtInput& in) { return in.scene.params.pbfFrame / in.scene.params.pbfSubsteps; }

int64_t PbfBytes(int64_t slots) { return 4 + 4 + 16 + 16 + 16 + 12 * ((slots + 15) / 16 * 16); }

void PbfWarnAtStart(const SceneSetup& scene, float height) {
  // The steady compression under a column of depth D is about K (1 + eps) g D dt^2 / (N s^2) at spacing
  // s: each substep's fall g dt^2 is carried up the column by N Jacobi iterations that reach one support
  // each. K = 0.195 from tank_rest (S^2 N x the mean compression 94-98.5 % over seven settings at eps = 1;
  // bench/pbf_still_water.py, docs/design/pbf.md).
  if (!(height > 0.0f)) return;
  const float g = Length(scene.gravity);
  const SolverParams& p = scene.params;
  const float dt = p.pbfFrame / p.pbfSubsteps, s = p.spacing;
  const float compression = 0.195f * (1.0f + p.pbfRelaxation) * g * height * dt * dt / (p.pbfIterations * s * s);
  if (compression > 0.05f) {
    const float substeps = std::ceil(p.pbfSubsteps * std::sqrt(compression / 0.02f));
    const std::string fix = substeps <= 16.0f ? Format("pbf_substeps %g would give about 2 %%", substeps)
                                              : std::string("more iterations or a coarser spacing would lower it");
    SPHXR_LOG_WARN("pbf: expect about %.0f%% mean compression at rest under the %.3g m column (%g substeps of %g "
                   "iterations a %.3g s frame at %.3g m spacing; it falls as 1 / (substeps^2 iterations)): %s",
                   100.0f * compression, height, p.pbfSubsteps, p.pbfIterations, p.pbfFrame, s, fix.c_str());
  }
}

float PbfSubstepsForSpacing(float sceneSubsteps, float sceneSpacing, float spacing) {
  if (!(spacing > 0.0f) || !(sceneSpacing > 0.0f)) return sceneSubsteps;
  // The 1e-3 keeps a ratio that rounding put a hair above a whole number (3 x 0.01 / 0.015) on it.
  const double s = std::ceil(static_cast<double>(sceneSubsteps) * sceneSpacing / spacing - 1e-3);
  return static_cast<float>(std::clamp(s, 1.0, 16.0));
}

std::string PbfParamsForSpacing(const SolverParams& scene, float spacing, SolverParams* out) {
  out->pbfSubsteps = PbfSubstepsForSpacing(scene.pbfSubsteps, scene.spacing, spacing);
  return Format("pbf_substeps %g, the scene's %g", out->pbfSubsteps, scene.pbfSubsteps);
}

}  // namespace sphxr::sim
