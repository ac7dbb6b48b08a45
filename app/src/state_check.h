#pragma once
// A state file is checked against the scene it is restored into as a scene is checked (sim's
// ValidateScene): finite is not enough. A particle outside the tank would be clamped back in (a huge
// density error), a body far away would move at an absurd speed in its first step, and particles with
// one id are not one particle's history.
#include "sphxr/app/state_file.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/params.h"

namespace sphxr::app {

/// The state's clock, particles, bodies and paddles against `scene`'s tank and spacing; an error names
/// what is damaged (RestoreState prefixes the file).
Status CheckAgainstScene(const StateFile& state, const sim::SceneSetup& scene);

}  // namespace sphxr::app
