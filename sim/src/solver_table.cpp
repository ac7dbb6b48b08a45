// The solver table (sphxr/sim/solver_table.h): one row per pressure solver.
#include "sphxr/sim/solver_table.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "sphxr/sim/solver.h"

namespace sphxr::sim {
namespace {

float SoundSpeedOf(const SolverParams& p) { return std::sqrt(p.exponent * p.stiffness / p.restDensity); }
float SmoothingOf(const SolverParams& p) { return 0.5f * p.spacing * p.supportFactor; }

/// The explicit artificial viscosity's diffusion limit (nu ~ alpha c h / 8), with the largest alpha
/// of the fluid and of the walls' friction.
float ViscosityDt(const SceneSetup& scene) {
  const SolverParams& p = scene.params;
  const TankFriction& f = scene.friction;
  float alpha = std::max(p.viscosity, p.boundaryViscosity);  // the paddles' default alpha too
  for (WallFriction w : {f.floor, f.top, f.xMin, f.xMax, f.zMin, f.zMax, f.obstacles}) {
    alpha = std::max(alpha, WallFrictionAlpha(p, w));
  }
  if (!(alpha > 0.0f)) return std::numeric_limits<float>::infinity();
  return 0.5f * SmoothingOf(p) / (alpha * SoundSpeedOf(p));
}

/// WCSPH: the acoustic CFL condition with the fastest particle or paddle point (Monaghan 1992; Becker &
/// Teschner 2007, sec. 5: nothing moves more than cfl * h per step), the force condition (a particle
/// moves at most ~h/16 per step under its acceleration) and the viscosity's limit.
float WcsphStableDt(const StableDtInput& in) {
  const SolverParams& p = in.scene.params;
  const float h = SmoothingOf(p);
  float dt = std::min(p.maxDt, p.cfl * h / (SoundSpeedOf(p) + in.maxSpeed));
  if (in.maxAccel > 0.0f) dt = std::min(dt, 0.25f * std::sqrt(h / in.maxAccel));
  return std::min(dt, ViscosityDt(in.scene));
}

/// DFSPH: the step follows the flow (Bender & Koschier 2017, sec. 5): no particle, fluid or paddle,
/// moves more than cfl * h per step. The pressure is implicit, so neither the sound speed nor the
/// acceleration limits it; the explicit viscosity still does.
float DfsphStableDt(const StableDtInput& in) {
  const SolverParams& p = in.scene.params;
  float dt = p.maxDt;
  if (in.maxSpeed > 0.0f) dt = std::min(dt, p.cfl * SmoothingOf(p) / in.maxSpeed);
  return std::min(dt, ViscosityDt(in.scene));
}

/// PBF: no stability bound from the sound speed or the flow (Macklin & Müller 2013): pbf_substeps steps
/// per pbf_frame, the displayed frame; the viscosity is XSPH's.
float PbfStableDt(const StableDtInput& in) { return in.scene.params.pbfFrame / in.scene.params.pbfSubsteps; }

int64_t NoBytes(int64_t) { return 0; }
/// sim/src/solvers/dfsph/dfsph.h: a kernel gradient per neighbour slot (12; on the CPU lane-blocked, in batches
/// of 16 slots: PairCacheStride), the boundary terms (16), factor, increment, neighbour count and the two
/// stiffnesses (20), the step's start velocity (16) and the error terms (8).
int64_t DfsphBytes(int64_t slots) { return 12 * ((slots + 15) / 16 * 16) + 16 + 20 + 16 + 8; }
/// sim/src/solvers/pbf/pbf.h: lambda and its sum over the step (8), the position corrections (16), the
/// boundary gradients (16); on the CPU the own terms (16) and the pair cache (12 a slot, in batches of
/// 16 slots: PairCacheStride). The step's start positions live in the acceleration field.
int64_t PbfBytes(int64_t slots) { return 4 + 4 + 16 + 16 + 16 + 12 * ((slots + 15) / 16 * 16); }

constexpr std::array<SolverStat, 4> kDfsphStats = {SolverStat::kDensityIterations, SolverStat::kDivergenceIterations,
                                                   SolverStat::kDensityError, SolverStat::kDivergenceError};
constexpr std::array<SolverStat, 2> kPbfStats = {SolverStat::kDensityIterations, SolverStat::kDensityError};

const std::array<SolverInfo, 3> kSolvers = {{
    {SolverMethod::kWcsph, "wcsph", "Becker & Teschner 2007 (weakly compressible SPH, Tait equation of state)",
     "weakly compressible SPH: explicit pressure from the Tait equation, a step bounded by the sound speed",
     /*wallDensity=*/true, /*deltaSph=*/true, /*reuse=*/true, ContactUse::kEveryParticle, /*acoustic=*/true, WcsphStableDt, {}, false, NoBytes,
     nullptr},
    {SolverMethod::kDfsph, "dfsph", "Bender & Koschier 2015, 2017 (divergence-free SPH)",
     "divergence-free SPH: implicit pressure from two Jacobi solves, a step that follows the flow speed "
     "([../design/dfsph.md](../design/dfsph.md))",
     false, false, false, ContactUse::kBelowRestDensity, false, DfsphStableDt, kDfsphStats, true, DfsphBytes, nullptr},
    {SolverMethod::kPbf, "pbf", "Macklin & Müller 2013 (position based fluids)",
     "position-based fluids: a fixed number of Jacobi iterations of the density constraint per step, one step "
     "per displayed frame, so its cost per frame is fixed ([../design/pbf.md](../design/pbf.md))",
     false, false, false, ContactUse::kNone, false, PbfStableDt, kPbfStats, false, PbfBytes,
     /*speedCapParam=*/"pbf_max_speed"},  // the prediction's and the corrections' velocity are capped
}};

}  // namespace

std::span<const SolverInfo> SolverTable() { return kSolvers; }

const SolverInfo& SolverInfoOf(SolverMethod method) {
  for (const SolverInfo& s : kSolvers) {
    if (s.method == method) return s;
  }
  SPHXR_ASSERT(false && "every SolverMethod has a row");
  return kSolvers[0];
}

const SolverInfo* FindSolver(const std::string& name) {
  for (const SolverInfo& s : kSolvers) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

std::string SolverNames() {
  std::string out;
  for (const SolverInfo& s : kSolvers) out += (out.empty() ? "" : ", ") + std::string(s.name);
  return out;
}

const char* SolverStatName(SolverStat stat) {
  switch (stat) {
    case SolverStat::kDensityIterations: return "density_iterations";
    case SolverStat::kDivergenceIterations: return "divergence_iterations";
    case SolverStat::kDensityError: return "solver_density_error";
    case SolverStat::kDivergenceError: return "solver_divergence_error";
  }
  return "?";
}

double SolverStatValue(const StepInfo& info, SolverStat stat) {
  switch (stat) {
    case SolverStat::kDensityIterations: return info.densityIterations;
    case SolverStat::kDivergenceIterations: return info.divergenceIterations;
    case SolverStat::kDensityError: return info.solverDensityError;
    case SolverStat::kDivergenceError: return info.solverDivergenceError;
  }
  return 0.0;
}

const char* SolverMethodName(SolverMethod method) { return SolverInfoOf(method).name; }

bool ParseSolverMethod(const std::string& text, SolverMethod* out) {
  const SolverInfo* s = FindSolver(text);
  if (s) *out = s->method;
  return s != nullptr;
}

}  // namespace sphxr::sim
