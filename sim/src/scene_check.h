#pragma once
// What Solver::Create and Solver::SetReuse check before they change anything (scene_check.cpp).
#include <cstdint>

#include "sphxr/common/status.h"
#include "sphxr/sim/params.h"

namespace sphxr::sim {

/// Every value of the scene, the grid it makes, and the particles and memory it needs (refused with a
/// message naming the key to change).
Status ValidateScene(const SceneSetup& scene);
Status ValidateReuse(const ReuseParams& reuse);
/// Reuse settings measured unstable, named when they are set (at start-up and by SetReuse).
void WarnAboutReuse(const ReuseParams& reuse);
/// Settings that run but will not give usable water, named once at start-up. `seeded`: the fluid
/// particles Create made.
void WarnAboutSettings(const SceneSetup& scene, int64_t seeded, float soundSpeed);

}  // namespace sphxr::sim
