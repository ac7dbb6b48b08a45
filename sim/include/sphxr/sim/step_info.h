#pragma once
// What a step reports: StepInfo (the last step), Totals (the run so far), the timed stages and the clamp
// sites. The pressure solver's own statistics are one SolveReport (solve_report.h) in each StepInfo.
#include <array>
#include <cstdint>
#include <string>

#include "sphxr/sim/params.h"
#include "sphxr/sim/solve_report.h"

namespace sphxr::sim {

/// Stages of one step, each timed.
/// kBodies: the moving boundaries' own work (placing and sorting their particles, the reaction on them,
/// the push-out); their terms inside the density and force loops count to those stages.
/// kDivergence, kPressure: DFSPH's two solves (its factor counts to kDensity); WCSPH leaves them 0.
/// kProbes: the pressure sensors and level gauges (Solver::SetProbes); 0 without probes.
/// kDiffuse: spray, foam and bubbles after the step (solver.diffuse, sphxr/sim/diffuse.h); 0 when off.
enum class Stage : int {
  kCells, kSort, kGrid, kActivity, kDensity, kForces, kIntegrate, kBodies, kDivergence, kPressure, kProbes, kDiffuse,
  kCount
};
const char* StageName(Stage stage);

struct StepInfo {
  double time = 0.0;             // s, simulated time after the step
  float dt = 0.0f;               // s, the step taken
  float maxSpeed = 0.0f;         // m/s
  float meanDensityError = 0.0f; // mean of max(0, rho/rho0 - 1) over fluid particles
  float maxDensityError = 0.0f;  // max of |rho/rho0 - 1| over fluid particles
  int32_t clamped = 0;           // fluid particles pushed back into the domain this step
  float activeFraction = 1.0f;   // fraction of fluid particles that computed density and forces (reuse)
  int32_t pushedOut = 0;         // fluid particles pushed out of a moving body this step
  SolveReport solve;             // the pressure solver's own statistics (its row's columns name them)
};

struct Totals {
  int64_t steps = 0;
  int64_t clampedEvents = 0;     // sum of StepInfo::clamped
  std::array<int64_t, kClampSites> clampedAt{};  // the same, per tank face and obstacle (ClampSiteName)
  int64_t particleSteps = 0;     // sum over steps of the fluid particles stepped (the clamp rate's denominator)
  int64_t dtClampedSteps = 0;    // steps where a fixed dt was clamped to the CFL limit
  int64_t pushedOutEvents = 0;   // sum of StepInfo::pushedOut
  int64_t densityIterations = 0;     // sums of StepInfo::solve's iterations
  int64_t divergenceIterations = 0;
  int64_t iterationCapSteps = 0;     // steps whose density solve stopped at max_iterations (SolveReport::densityCapped)
  std::array<double, static_cast<int>(Stage::kCount)> stageSeconds{};
  double stepSeconds = 0.0;      // wall time in Step()
};

/// "x- wall", "x+ wall", "floor", "top", "z- wall", "z+ wall", then "obstacles[k]" (params.h kClampSites).
std::string ClampSiteName(int site);
/// The clamp rate above which the walls leak (the solver warns once, naming the wall): 1 in 10,000
/// particle-steps. Below it the clamp is a safety net, not what holds the water.
inline constexpr double kLeakingClampRate = 1e-4;

}  // namespace sphxr::sim
