#include "state_check.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "sphxr/common/log.h"

namespace sphxr::app {
namespace {

constexpr double kMaxFluidSpeed = 1000.0;  // m/s: a scene's fluid block may start at most this fast

// The smallest step a state may ask for: the smallest solver.max_dt a scene may set.
constexpr double kMinResolvedStep = 1e-7;  // s

}  // namespace

Status CheckAgainstScene(const StateFile& state, const sim::SceneSetup& scene) {
  // The clock's last maxima set the first step (its CFL and force conditions): a damaged maximum would
  // collapse the time step, and the run would stop naming neither the file nor the value.
  const double speed = state.clock.lastMaxSpeed, accel = state.clock.lastMaxAccel;
  if (!(speed <= kMaxFluidSpeed)) {
    return Status::Error(Format("the clock's last maximum speed %g m/s is beyond the %g m/s a fluid may have: damaged",
                                speed, kMaxFluidSpeed));
  }
  // WCSPH's force condition, dt = 0.25 sqrt(h / a), with the state's smoothing length h.
  const double h = 0.5 * scene.params.spacing * scene.params.supportFactor;
  const double maxAccel = h * std::pow(0.25 / kMinResolvedStep, 2.0);
  if (!(accel <= maxAccel)) {
    return Status::Error(Format("the clock's last maximum acceleration %g m/s^2 asks for a step below %g s (at most "
                                "%.3g m/s^2 at spacing %g m): damaged",
                                accel, kMinResolvedStep, maxAccel, scene.params.spacing));
  }
  const sim::HostFluid& f = state.fluid;
  const float slack = scene.params.spacing;  // the domain clamp keeps particles inside the walls
  const sim::Aabb& t = scene.tank;
  for (size_t i = 0; i < f.size(); ++i) {
    const sim::Vec4 p = f.position[i];
    const float top = t.max.y + slack;  // (an open tank's domain ends at its rim too)
    if (!(p.x >= t.min.x - slack && p.x <= t.max.x + slack && p.y >= t.min.y - slack && p.y <= top &&
          p.z >= t.min.z - slack && p.z <= t.max.z + slack)) {
      return Status::Error(Format("particle %zu (id %u) at [%g %g %g] is outside the tank [%g %g %g] to [%g %g %g]: "
                                  "saved from another scene, or damaged",
                                  i, f.id[i], p.x, p.y, p.z, t.min.x, t.min.y, t.min.z, t.max.x, t.max.y, t.max.z));
    }
    const sim::Vec4 v = f.velocity[i];
    const double speed = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
    if (!(speed <= kMaxFluidSpeed)) {
      return Status::Error(Format("particle %zu (id %u) moves at %g m/s; at most %g m/s is supported: damaged", i,
                                  f.id[i], speed, kMaxFluidSpeed));
    }
  }
  std::vector<uint32_t> ids(f.id);
  std::sort(ids.begin(), ids.end());
  if (const auto twin = std::adjacent_find(ids.begin(), ids.end()); twin != ids.end()) {
    return Status::Error(Format("particle id %u appears twice: damaged", *twin));
  }
  // Bodies (paddles) may be withdrawn above the water, not far away: within the tank's diagonal of it.
  const double reach = Length(t.max - t.min);
  auto near = [&](const sim::Vec3& x) {
    const double dx = std::max({double(t.min.x) - x.x, 0.0, double(x.x) - t.max.x});
    const double dy = std::max({double(t.min.y) - x.y, 0.0, double(x.y) - t.max.y});
    const double dz = std::max({double(t.min.z) - x.z, 0.0, double(x.z) - t.max.z});
    return std::sqrt(dx * dx + dy * dy + dz * dz) <= reach;
  };
  for (size_t k = 0; k < state.bodies.size(); ++k) {
    const sim::BodyMotionState& m = state.bodies[k];
    for (const sim::Pose* pose : {&m.pose, &m.from, &m.to}) {
      if (!Finite(pose->position) || !near(pose->position)) {
        return Status::Error(Format("body %zu's pose [%g %g %g] is more than the tank's diagonal (%g m) from the tank: "
                                    "damaged",
                                    k, pose->position.x, pose->position.y, pose->position.z, reach));
      }
    }
    const double speed = Finite(m.velocity) ? double(Length(m.velocity)) : HUGE_VAL;
    if (!(speed <= kMaxFluidSpeed)) {
      return Status::Error(Format("body %zu moves at %g m/s; at most %g m/s is supported: damaged", k, speed, kMaxFluidSpeed));
    }
  }
  for (size_t k = 0; k < state.paddles.size(); ++k) {
    if (!near(state.paddles[k].state.commanded.position)) {
      return Status::Error(Format("paddle %zu's commanded pose is more than the tank's diagonal from the tank: damaged", k));
    }
  }
  return Status::Ok();
}

}  // namespace sphxr::app
