#pragma once
// --quality auto: pick the pressure solver and the particle spacing (and the surface cell size) so that a
// scene runs in real time on the machine it finds. Measured, not guessed: a few steps of the scene are
// timed under each method, the faster kept, and the spacing is scaled by the cost model (particles ~
// h^-3, stable dt ~ h, so simulated seconds per wall second ~ h^4), then checked once more there. A
// method's own parameters follow the spacing as its row of the solver table says (paramsForSpacing: PBF's
// substeps, which makes its cost ~ h^-4 as well).
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct QualityChoice {
  sim::SolverMethod method = sim::SolverMethod::kWcsph;  // the faster at the scene's spacing
  float spacing = 0.0f;          // m
  float surfaceCellSize = 0.0f;  // m, for the surface mesh (HPMC) when it lands: one spacing
  sim::SolverParams params;      // the scene's, with the chosen spacing and the method's own parameters for it
  double realtime = 0.0;         // simulated s per wall s measured at the chosen spacing
  int fluid = 0;                 // particles at the chosen spacing
  std::string summary;           // the logged line
};

/// The spacing that reaches `target` simulated seconds per wall second, from a measured `realtime` at
/// `spacing` (cost ~ h^-4), clamped to [minSpacing, maxSpacing].
float SpacingForRealtime(float spacing, double realtime, double target, float minSpacing, float maxSpacing);

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
