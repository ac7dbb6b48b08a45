// Solver::Settle: FIRE (Bitzek et al. 2006) on the solver's own steps, before a run
// (docs/design/settle.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "backend.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {

Status Solver::Settle(double seconds, SettleReport* report, const SettleProgress& progress) {
  if (!(seconds > 0.0) || !std::isfinite(seconds)) {
    return Status::Error("settle time " + std::to_string(seconds) + " s: must be a positive number of seconds");
  }
  if (m_totals.steps != 0) return Status::Error("settle: only before the first step (it replaces the start)");
  const auto begin = std::chrono::steady_clock::now();
  const ReuseParams reuse = m_scene.reuse;
  if (reuse.enabled) {  // every particle computes while settling
    ReuseParams off = reuse;
    off.enabled = false;
    if (Status s = SetReuse(off); !s) return s;
  }
  // A failed settle still gives the scene its reuse back (the caller may go on, or save).
  struct RestoreReuse {
    Solver* solver;
    ReuseParams reuse;
    ~RestoreReuse() {
      if (reuse.enabled && !solver->m_scene.reuse.enabled) (void)solver->SetReuse(reuse);  // validated before
    }
  } restoreReuse{this, reuse};
  SettleReport r;
  m_leakWarned = true;  // the settle's steps are not the run's: it clamps what it relaxes
  double alpha = 0.1;
  int downhill = 0;
  while (m_last.time < seconds) {
    if (Status s = Step(); !s) return s;
    ++r.steps;
    // FIRE (Bitzek et al. 2006) with the solver's CFL step as its step: mix the velocities toward the
    // forces while they do work, stop everything when they do not.
    const FireSums sums = m_backend->FireReduce();
    r.maxAccel = m_maxAccel;  // this step's largest |a|, from its StepReduction
    if (!std::isfinite(sums.power) || !std::isfinite(sums.accel2)) {
      return Status::Error(Format("settle: the state became non-finite at step %lld (t = %.4g s); rerun with --validate "
                                  "to find the stage and particle",
                                  static_cast<long long>(r.steps), m_last.time));
    }
    if (sums.power > 0.0) {
      const double mix = alpha * std::sqrt(sums.speed2 / std::max(sums.accel2, 1e-30));
      m_backend->FireMix(static_cast<float>(1.0 - alpha), static_cast<float>(mix));
      if (++downhill > 5) alpha *= 0.99;
    } else {
      m_backend->FireMix(0.0f, 0.0f);
      alpha = 0.1;
      downhill = 0;
    }
    if (progress && !progress(std::min(m_last.time, seconds))) {
      r.stopped = true;
      break;
    }
  }
  m_backend->FireMix(0.0f, 0.0f);
  m_backend->UploadDiffuse(HostDiffuse{});  // the settle's spray and foam go with its clock
  r.time = m_last.time;
  for (BodyMotion& b : m_bodies) HoldBody(&b, b.pose, 0.0);  // where it is, at rest, on the restarted clock
  m_last = StepInfo{};
  m_totals = Totals{};
  m_leakWarned = false;
  m_maxAccel = 0.0f;
  if (reuse.enabled) {
    if (Status s = SetReuse(reuse); !s) return s;
  }
  r.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  if (report) *report = r;
  return Status::Ok();
}

}  // namespace sphxr::sim
