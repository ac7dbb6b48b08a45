// A solver's state in and out: downloads, uploads, the clock and a restart from a saved state, and a
// change of the reuse parameters (which restarts every particle's idle count).
#include <algorithm>
#include <cmath>

#include "backend.h"
#include "scene_check.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {

void Solver::Download(HostFluid* out) const { m_backend->Download(out); }
void Solver::DownloadBoundary(HostBoundary* out) const { m_backend->DownloadBoundary(out); }

Status Solver::CheckFluidSizes(const HostFluid& fluid, const char* who) const {
  if (static_cast<int>(fluid.size()) != FluidCount()) {
    return Status::Error(Format("%s: %zu particles given, the solver has %d", who, fluid.size(), FluidCount()));
  }
#define SPHXR_CHECK_SIZE(type, name)                                                  \
  if (fluid.name.size() != fluid.size())                                              \
    return Status::Error(std::string(who) + ": field '" #name "' has a different size than position");
  SPHXR_FLUID_FIELDS(SPHXR_CHECK_SIZE)
#undef SPHXR_CHECK_SIZE
  return Status::Ok();
}

Status Solver::Upload(const HostFluid& fluid) {
  if (Status s = CheckFluidSizes(fluid, "Upload"); !s) return s;
  m_backend->Upload(fluid);
  return Status::Ok();
}

SolverClock Solver::Clock() const {
  SolverClock c;
  c.time = m_last.time;
  c.lastMaxSpeed = m_last.maxSpeed;
  c.lastMaxAccel = m_maxAccel;
  c.steps = m_stepBase + m_totals.steps;
  return c;
}

Status Solver::Restore(const HostFluid& fluid, const SolverClock& clock) {
  if (m_totals.steps != 0) return Status::Error("restore: only before the first step (it replaces the start)");
  // A clock past 1e9 s (32 years) is damage, not a run: there a step of ~1e-4 s no longer moves a double
  // clock, and frame numbers computed from it overflow (a flipped exponent bit hung the headless runner).
  if (!std::isfinite(clock.time) || clock.time < 0.0 || clock.time > 1e9 || !std::isfinite(clock.lastMaxSpeed) ||
      clock.lastMaxSpeed < 0.0f || !std::isfinite(clock.lastMaxAccel) || clock.lastMaxAccel < 0.0f || clock.steps < 0) {
    return Status::Error(Format("restore: the clock (t = %g s, last max speed %g m/s, last max |a| %g m/s^2, %lld "
                                "steps) must be finite, not negative, and t at most 1e9 s",
                                clock.time, clock.lastMaxSpeed, clock.lastMaxAccel, static_cast<long long>(clock.steps)));
  }
  if (Status s = CheckFluidSizes(fluid, "restore"); !s) return s;
  for (size_t i = 0; i < fluid.size(); ++i) {
    // With reuse, a particle restored idle uses its saved density, pressure and pressure term in its
    // neighbours' first steps (they divide by its density): all must be sound.
    if (!Finite(Xyz(fluid.position[i])) || !Finite(Xyz(fluid.velocity[i])) || !Finite(Xyz(fluid.acceleration[i])) ||
        !(fluid.density[i] > 0.0f) || !std::isfinite(fluid.density[i]) || !std::isfinite(fluid.pressure[i]) ||
        !std::isfinite(fluid.pressureTerm[i])) {
      return Status::Error(Format("restore: particle %zu (id %u) has a non-finite position, velocity, acceleration, "
                                  "pressure or pressure term, or a density that is not a positive number",
                                  i, fluid.id[i]));
    }
  }
  // Idle counts saved under other reuse parameters (or with reuse on, now off) that this run's IDLE does
  // not allow start active, so that no particle reuses longer than IDLE steps.
  const int32_t maxIdle = m_scene.reuse.enabled ? m_scene.reuse.idle : -1;
  auto allowed = [maxIdle](int32_t ic) { return ic <= maxIdle && ic >= -2 - maxIdle; };
  if (std::all_of(fluid.idle.begin(), fluid.idle.end(), allowed)) {
    m_backend->Upload(fluid);
  } else {
    HostFluid clamped = fluid;
    for (int32_t& ic : clamped.idle) {
      if (!allowed(ic)) ic = -1;
    }
    m_backend->Upload(clamped);
  }
  m_last = StepInfo{};
  m_last.time = clock.time;
  m_last.maxSpeed = clock.lastMaxSpeed;
  m_maxAccel = clock.lastMaxAccel;
  m_totals = Totals{};
  m_stepBase = clock.steps;
  for (BodyMotion& b : m_bodies) HoldBody(&b, b.pose, clock.time);  // where it is, at rest, on the restored clock
  return Status::Ok();
}

int Solver::DiffuseCount() const { return m_backend->DiffuseCount(); }
void Solver::DownloadDiffuse(HostDiffuse* out) const { m_backend->DownloadDiffuse(out); }

Status Solver::RestoreDiffuse(const HostDiffuse& diffuse) {
  if (diffuse.count < 0 || diffuse.position.size() != static_cast<size_t>(diffuse.count) ||
      diffuse.velocity.size() != static_cast<size_t>(diffuse.count)) {
    return Status::Error(Format("restore: %d diffuse particles with %zu positions and %zu velocities", diffuse.count,
                                diffuse.position.size(), diffuse.velocity.size()));
  }
  for (int i = 0; i < diffuse.count; ++i) {
    const Vec4 p = diffuse.position[i], v = diffuse.velocity[i];
    const bool kind = v.w == 0.0f || v.w == 1.0f || v.w == 2.0f;
    if (!Finite(Xyz(p)) || !std::isfinite(p.w) || !Finite(Xyz(v)) || !kind) {
      return Status::Error(Format("restore: diffuse particle %d has a non-finite position, lifetime or velocity, or a "
                                  "kind (%g) that is not 0, 1 or 2", i, v.w));
    }
  }
  if (!m_scene.params.diffuse) {
    if (diffuse.count > 0) SPHXR_LOG_INFO("restore: %d diffuse particles left out: solver.diffuse is off", diffuse.count);
    return Status::Ok();
  }
  const int left = m_backend->UploadDiffuse(diffuse);
  if (left > 0) {
    SPHXR_LOG_INFO("restore: the oldest %d of %d diffuse particles left out: solver.diffuse_capacity is %d", left,
                   diffuse.count, static_cast<int>(m_scene.params.diffuseCapacity));
  }
  return Status::Ok();
}

Status Solver::SetPbfFrame(float seconds) {
  SceneSetup changed = m_scene;
  changed.params.pbfFrame = seconds;
  if (Status s = ValidateScene(changed); !s) return s;
  m_scene.params.pbfFrame = seconds;
  SceneChanged();
  return Status::Ok();
}

Status Solver::SetReuse(const ReuseParams& reuse) {
  if (Status s = ValidateReuse(reuse); !s) return s;
  m_scene.reuse = reuse;
  SceneChanged();
  WarnAboutReuse(reuse);
  HostFluid fluid;
  m_backend->Download(&fluid);
  std::fill(fluid.idle.begin(), fluid.idle.end(), -1);
  m_backend->Upload(fluid);
  return Status::Ok();
}

}  // namespace sphxr::sim
