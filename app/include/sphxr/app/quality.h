#pragma once
// --quality auto: pick the pressure solver and the particle spacing (and the surface cell size) so that a
// scene runs in real time on the machine it finds. Measured, not guessed: a few steps of the scene are
// timed under each method, the faster kept, and the spacing is scaled by the cost model (particles ~
// h^-3, stable dt ~ h, so simulated seconds per wall second ~ h^4), then checked once more there. Under
// PBF the substeps follow the spacing (PbfSubstepsForSpacing), which makes its cost ~ h^-4 as well.
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct QualityChoice {
  sim::SolverMethod method = sim::SolverMethod::kWcsph;  // the faster at the scene's spacing
  float spacing = 0.0f;          // m
  float surfaceCellSize = 0.0f;  // m, for the surface mesh (HPMC) when it lands: one spacing
  float pbfSubsteps = 0.0f;      // under PBF: the substeps that keep the scene's step per spacing (0: other methods)
  double realtime = 0.0;         // simulated s per wall s measured at the chosen spacing
  int fluid = 0;                 // particles at the chosen spacing
  std::string summary;           // the logged line
};

/// The spacing that reaches `target` simulated seconds per wall second, from a measured `realtime` at
/// `spacing` (cost ~ h^-4), clamped to [minSpacing, maxSpacing].
float SpacingForRealtime(float spacing, double realtime, double target, float minSpacing, float maxSpacing);

/// PBF's substeps a frame at `spacing` for a scene that takes `sceneSubsteps` at `sceneSpacing`: the
/// fewest that keep the step per spacing (dt / h) at most the scene's, within pbf_substeps' range [1, 16].
/// PBF's rest compression goes as g D dt^2 / (N h^2) (docs/design/pbf.md), so a coarser spacing keeps the
/// scene's compression and stability with fewer substeps, and a finer one needs more.
float PbfSubstepsForSpacing(float sceneSubsteps, float sceneSpacing, float spacing);

/// Under --quality auto, spray, foam and bubbles are a luxury: when the water cannot keep real time at
/// the chosen spacing (`realtime` < 1 simulated s per wall s) the diffuse stage is turned off (its cost
/// grows with the particles it spawns, faster the further behind the water falls), unless the command
/// line set `diffuse` itself. True when it turned them off.
bool TurnOffDiffuseOutOfRealTime(double realtime, bool setByUser, sim::SolverParams* params);

/// Times the scene for about `budgetSeconds` of wall time (twice at most) and picks the spacing. The
/// finest spacing tried is half the scene's, the coarsest four times it.
Status ChooseQuality(const sim::SceneSetup& scene, const sim::SolverConfig& config, double target,
                     double budgetSeconds, QualityChoice* out);

}  // namespace sphxr::app
