// Solver's step: the time step (the method's stable step, solver.fixed_dt), the validate hook, the
// backend's step, and what it reports (StepInfo, Totals and the warnings they raise).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "backend.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {

const char* StageName(Stage stage) {
  switch (stage) {
    case Stage::kCells: return "cells";
    case Stage::kSort: return "sort";
    case Stage::kGrid: return "grid";
    case Stage::kActivity: return "activity";
    case Stage::kDensity: return "density";
    case Stage::kForces: return "forces";
    case Stage::kIntegrate: return "integrate";
    case Stage::kBodies: return "bodies";
    case Stage::kDivergence: return "divergence";
    case Stage::kPressure: return "pressure";
    case Stage::kProbes: return "probes";
    case Stage::kDiffuse: return "diffuse";
    default: return "?";
  }
}

std::string ClampSiteName(int site) {
  static const char* const kFaces[kTankFaces] = {"x- wall", "x+ wall", "floor", "top", "z- wall", "z+ wall"};
  SPHXR_ASSERT(site >= 0 && site < kClampSites);
  return site < kTankFaces ? kFaces[site] : Format("obstacles[%d]", site - kTankFaces);
}

void Solver::WarnIfWallsLeak() {
  // Judged once the run has taken 100,000 particle-steps (a few steps of a large scene, some tens of a
  // small one), then at most once per run.
  if (m_leakWarned || m_totals.particleSteps < 100000) return;
  const double rate = static_cast<double>(m_totals.clampedEvents) / static_cast<double>(m_totals.particleSteps);
  if (rate <= kLeakingClampRate) return;
  m_leakWarned = true;
  int worst = 0;
  for (int k = 1; k < kClampSites; ++k) {
    if (m_totals.clampedAt[k] > m_totals.clampedAt[worst]) worst = k;
  }
  const double share = static_cast<double>(m_totals.clampedAt[worst]) / static_cast<double>(m_totals.clampedEvents);
  SPHXR_LOG_WARN("the walls leak: %.3g clamps per 1,000 particle-steps by t = %.3g s (a safety net clamps under "
                 "%.2g), %.0f %% of them at the %s (logged once; docs/design/walls.md)",
                 1000.0 * rate, m_last.time, 1000.0 * kLeakingClampRate, 100.0 * share, ClampSiteName(worst).c_str());
}

float Solver::StableDt() const {
  const float speed = std::max(m_last.maxSpeed, MaxBodySpeed());
  const float accel = std::max(m_maxAccel, Length(m_scene.gravity));
  return SolverInfoOf(m_scene.method).stableDt(StableDtInput{m_scene, speed, accel});
}

Status Solver::Step() {
  const auto begin = std::chrono::steady_clock::now();
  float dt = 0.0f;
  if (Status s = NextDt(&dt); !s) return s;
  const int64_t stepNumber = m_stepBase + m_totals.steps + 1;
  HostFluid host;  // the validate hook's download
  StageHook hook;
  if (m_config.validate) {
    if (Status s = ValidateStart(stepNumber, &host); !s) return s;
    hook = ValidateHook(stepNumber, &host);
  }
  Physics physics = *m_physics;
  physics.reuseSyncStep = stepNumber % (physics.reuseIdle + 1) == 0;
  physics.step = stepNumber;
  const std::vector<BodyState> states = StartBodyMotion(dt);
  StepReduction red;
  SolveReport report;
  double* stageSeconds = m_config.stageTimes ? m_totals.stageSeconds.data() : nullptr;
  if (Status s = m_backend->Step(dt, physics, &red, &report, stageSeconds, hook); !s) return s;
  EndBodyMotion(states);
  if (red.nonFinite > 0) {
    // Without --validate nothing else would notice: the step's maxima drop NaN, and a NaN particle
    // sits in the grid's last cell with no neighbours, exported and saved as NaN.
    return Status::Error(Format("%d fluid particles became non-finite (NaN or infinite position, velocity, acceleration "
                                "or density) in the step from t = %.6g s: the simulation has become unstable; rerun "
                                "with --validate to find the stage and particle, and lower solver.fixed_dt or raise "
                                "solver.stiffness",
                                red.nonFinite, m_last.time));
  }
  if (!m_probes.Empty()) ReadProbes(m_probes, m_probeDry, m_last.time, stepNumber - 1, &m_probeSample);
  RecordStep(dt, red, report);
  WarnIfWallsLeak();
  WarnIfIterationCapped(report);
  m_totals.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return Status::Ok();
}

Status Solver::NextDt(float* out) {
  float dt = StableDt();
  const float fixedDt = m_scene.params.fixedDt;
  if (fixedDt > 0.0f) {
    if (fixedDt <= dt) {
      dt = fixedDt;
    } else {
      ++m_totals.dtClampedSteps;
      if (!m_dtClampLogged) {
        m_dtClampLogged = true;
        SPHXR_LOG_WARN("fixed_dt = %g s is above the stability limit %g s (CFL %g, sound speed %.3g m/s) at t = %.4g s: "
                       "clamped to the limit (logged once)",
                       fixedDt, dt, m_scene.params.cfl, SoundSpeed(), m_last.time);
      }
    }
  }
  // A step that cannot advance the clock would loop forever (the force condition under an exploding
  // acceleration): say so instead.
  if (!(dt > 0.0f) || !std::isfinite(dt) || m_last.time + dt == m_last.time) {
    return Status::Error(Format("the time step collapsed to %g s at t = %.6g s (largest acceleration %g m/s^2): the "
                                "simulation has become unstable",
                                dt, m_last.time, m_maxAccel));
  }
  *out = dt;
  return Status::Ok();
}

Status Solver::ValidateStart(int64_t stepNumber, HostFluid* host) const {
  m_backend->Download(host);
  for (size_t i = 0; i < host->size(); ++i) {
    if (!Finite(Xyz(host->position[i])) || !Finite(Xyz(host->velocity[i]))) {
      const char* field = Finite(Xyz(host->position[i])) ? "velocity" : "position";
      return Status::Error(Format("validate: non-finite %s of particle %u at the start of step %lld", field,
                                  host->id[i], static_cast<long long>(stepNumber)));
    }
  }
  return Status::Ok();
}

StageHook Solver::ValidateHook(int64_t stepNumber, HostFluid* host) const {
  return [this, stepNumber, host](Stage stage) -> Status {
    m_backend->Download(host);
    for (size_t i = 0; i < host->size(); ++i) {
      const char* bad = nullptr;
      if (!Finite(Xyz(host->position[i]))) bad = "position";
      else if (!Finite(Xyz(host->velocity[i]))) bad = "velocity";
      else if ((stage == Stage::kForces || stage == Stage::kIntegrate) && !Finite(Xyz(host->acceleration[i])))
        bad = "acceleration";
      else if (stage >= Stage::kDensity && !std::isfinite(host->density[i])) bad = "density";
      else if (stage >= Stage::kDensity && !std::isfinite(host->pressure[i])) bad = "pressure";
      if (bad) {
        return Status::Error(Format("validate: non-finite %s of particle %u after stage '%s' in step %lld", bad,
                                    host->id[i], StageName(stage), static_cast<long long>(stepNumber)));
      }
    }
    return Status::Ok();
  };
}

void Solver::RecordStep(float dt, const StepReduction& red, const SolveReport& report) {
  m_last.time += dt;
  m_last.dt = dt;
  m_last.maxSpeed = std::sqrt(red.maxSpeed2);
  m_maxAccel = std::sqrt(red.maxAccel2);
  const int n = FluidCount();
  m_last.meanDensityError = n > 0 ? static_cast<float>(red.sumCompression / n) : 0.0f;
  m_last.maxDensityError = red.maxDensityError;
  m_last.clamped = red.clamped;
  m_last.activeFraction = n > 0 ? static_cast<float>(red.computed) / static_cast<float>(n) : 1.0f;
  m_last.pushedOut = red.pushed;
  m_last.solve = report;
  m_totals.steps += 1;
  m_totals.clampedEvents += red.clamped;
  for (int k = 0; k < kClampSites; ++k) m_totals.clampedAt[k] += red.clampedAt[k];
  m_totals.particleSteps += n;
  m_totals.pushedOutEvents += red.pushed;
  m_totals.densityIterations += report.densityIterations;
  m_totals.divergenceIterations += report.divergenceIterations;
}

void Solver::WarnIfIterationCapped(const SolveReport& report) {
  if (!report.densityCapped) return;
  // The solve stopped short: the water is more compressed than asked this step. Named with the error
  // reached, at most once per simulated second (a hard impact hits the cap for many steps in a row).
  ++m_totals.iterationCapSteps;
  if (m_iterationWarnTime >= 0.0 && m_last.time < m_iterationWarnTime + 1.0) return;
  m_iterationWarnTime = m_last.time;
  const SolverParams& p = m_scene.params;
  SPHXR_LOG_WARN("%s: the density solve reached max_iterations = %d at t = %.4g s with a mean compression of "
                 "%.3g %% (density_tolerance %g %%; %lld such steps so far): raise solver.max_iterations or lower "
                 "solver.cfl",
                 SolverMethodName(m_scene.method), static_cast<int>(p.maxIterations), m_last.time,
                 100.0 * report.densityError, 100.0 * (0.01f * p.densityTolerance),
                 static_cast<long long>(m_totals.iterationCapSteps));
}

}  // namespace sphxr::sim
