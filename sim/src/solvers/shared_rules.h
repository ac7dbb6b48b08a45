#pragma once
// What the methods' rules (solvers/<method>/<method>_rules.cpp) share: the scene's sound speed, the
// smoothing length and the explicit viscosity's time-step limit.
#include "sphxr/sim/params.h"

namespace sphxr::sim {

float SoundSpeedOf(const SolverParams& p);  // sqrt(B gamma / rho0), m/s
float SmoothingOf(const SolverParams& p);   // h = support / 2, m
/// The explicit artificial viscosity's diffusion limit (nu ~ alpha c h / 8), with the largest alpha
/// of the fluid and of the walls' friction; infinity without viscosity.
float ViscosityDt(const SceneSetup& scene);

}  // namespace sphxr::sim
