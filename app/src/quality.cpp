#include "sphxr/app/quality.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "sphxr/common/log.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::app {
namespace {

/// Simulated seconds per wall second over steps after the first (which pays for first-touch allocation).
Status Measure(const sim::SceneSetup& scene, const sim::SolverConfig& config, double budgetSeconds, double* realtime,
               int* fluid) {
  std::unique_ptr<sim::Solver> solver;
  if (Status s = sim::Solver::Create(scene, config, &solver); !s) return s;
  *fluid = solver->FluidCount();
  if (Status s = solver->Step(); !s) return s;
  const double t0 = solver->Time();
  const auto w0 = std::chrono::steady_clock::now();
  double wall = 0.0;
  int steps = 0;
  while (steps < 3 || wall < budgetSeconds) {
    if (Status s = solver->Step(); !s) return s;
    ++steps;
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    if (steps >= 200) break;
  }
  *realtime = (solver->Time() - t0) / std::max(wall, 1e-9);
  return Status::Ok();
}

}  // namespace

float SpacingForRealtime(float spacing, double realtime, double target, float minSpacing, float maxSpacing) {
  if (!(realtime > 0.0) || !(target > 0.0)) return maxSpacing;
  const double h = spacing * std::pow(target / realtime, 0.25);
  return static_cast<float>(std::clamp(h, static_cast<double>(minSpacing), static_cast<double>(maxSpacing)));
}

Status ChooseQuality(const sim::SceneSetup& scene, const sim::SolverConfig& config, double target, double budgetSeconds,
                     QualityChoice* out) {
  *out = QualityChoice{};
  const float h0 = scene.params.spacing;
  // Coarser than 4 spacings, or below kMinFluid particles, a scene stops showing what it is about.
  constexpr double kMinFluid = 2000.0;
  const double n = static_cast<double>(sim::CountParticles(scene).fluid);
  const float minH = 0.5f * h0;
  const float maxH = std::max(h0, std::min(4.0f * h0, static_cast<float>(h0 * std::cbrt(std::max(n, 1.0) / kMinFluid))));
  // The first steps of a scene are calm; splashes shorten the step later. Aim 30 % above the target.
  const double aim = 1.3 * target;
  // The method first: every row of the solver table measured at the scene's spacing in half the budget,
  // the fastest kept (WCSPH's step follows the sound speed, DFSPH's the flow, PBF's the frame).
  const double share = 0.5 * budgetSeconds / static_cast<double>(sim::SolverTable().size());
  double r0 = 0.0;
  int n0 = 0;
  sim::SceneSetup trial = scene;
  if (Status s = Measure(scene, config, share, &r0, &n0); !s) return s;
  for (const sim::SolverInfo& row : sim::SolverTable()) {  // every other method, measured alike
    if (row.method == scene.method) continue;
    sim::SceneSetup other = scene;
    other.method = row.method;
    double r = 0.0;
    int n = 0;
    if (Status s = Measure(other, config, share, &r, &n); s && r > r0) {
      r0 = r;
      trial.method = other.method;
    }
  }
  out->method = trial.method;
  // The method's own parameters that follow the spacing (its row; nullptr: none).
  const auto forSpacing = sim::SolverInfoOf(trial.method).paramsForSpacing;
  std::string ownParams;
  trial.params.spacing = SpacingForRealtime(h0, r0, aim, minH, maxH);
  if (forSpacing) ownParams = forSpacing(scene.params, trial.params.spacing, &trial.params);
  double r1 = r0;
  int n1 = n0;
  if (trial.params.spacing != h0) {
    if (Status s = Measure(trial, config, 0.5 * budgetSeconds, &r1, &n1); !s) return s;
    // One correction from the second measurement (the h^4 model is rough at small particle counts).
    const float h2 = SpacingForRealtime(trial.params.spacing, r1, aim, minH, maxH);
    if (r1 < target && h2 > trial.params.spacing) trial.params.spacing = h2;
    if (forSpacing) ownParams = forSpacing(scene.params, trial.params.spacing, &trial.params);
  }
  out->params = trial.params;
  out->spacing = trial.params.spacing;
  out->surfaceCellSize = trial.params.spacing;
  out->realtime = r1;
  out->fluid = static_cast<int>(sim::CountParticles(trial).fluid);
  out->summary = Format("quality auto: method %s, spacing %.4g m (scene %.4g m), %d fluid particles, surface cell %.4g m; "
                        "measured %.3g simulated s per wall s at the scene's spacing (%d particles), %.3g at %.4g m",
                        sim::SolverMethodName(out->method), out->spacing, h0, out->fluid, out->surfaceCellSize, r0, n0,
                        r1, trial.params.spacing);
  if (!ownParams.empty()) out->summary += " (" + ownParams + Format(" at %.4g m)", h0);
  if (r1 < target) {
    out->summary += Format("; real time is out of reach on this machine at %g particles or more: the window shows "
                           "the simulation slower than real time", kMinFluid);
  }
  SPHXR_LOG_INFO("%s", out->summary.c_str());
  return Status::Ok();
}

bool TurnOffDiffuseOutOfRealTime(double realtime, bool setByUser, sim::SolverParams* params) {
  if (params->diffuse <= 0.0f || setByUser || !(realtime < 1.0)) return false;
  params->diffuse = 0.0f;
  return true;
}

}  // namespace sphxr::app
