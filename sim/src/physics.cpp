// MakePhysics: the constants every stage shares, from the scene (backend.h). A pressure solver's own
// constants are its own (solvers/<method>/<method>_constants.h, PressureSolver::Init).
#include <algorithm>
#include <cmath>

#include "backend.h"
#include "sampling.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {
namespace {

/// Activity-based reuse (Huang et al. 2013, §3.3), when the method and the density model allow it.
void SetReuseConstants(const SceneSetup& scene, const SolverInfo& method, Physics* ph) {
  const SolverParams& p = scene.params;
  const ReuseParams& r = scene.reuse;
  // Reuse holds a summation density: an integrated density cannot skip steps.
  ph->reuseEnabled = r.enabled && method.reuse && !ph->continuityDensity;
  ph->reuseDelta1 = r.delta1;
  ph->reuseDelta2 = r.delta2;
  ph->reuseThreshold = r.threshold;
  ph->reuseIdle = r.idle;
  // P_pc: the Tait pressure at 1 % compression unless the scene sets it (our copy of the paper stops
  // before its parameter values); N_CPN: the rest lattice's particles per cell, (cell / dx)^3.
  const float pc = r.pressureScale > 0.0f ? r.pressureScale : p.stiffness * (std::pow(1.01f, p.exponent) - 1.0f);
  ph->reuseInvPressureScale = 1.0f / pc;
  ph->reuseCellCount = r.cellCount > 0.0f ? r.cellCount : p.supportFactor * p.supportFactor * p.supportFactor;
  ph->reuseSyncStep = true;  // Solver::Step sets it from the step's number
}

/// The clamp box, the obstacles and the walls' contact (needs ph->soundSpeed).
void SetTankConstants(const SceneSetup& scene, const SolverInfo& method, Physics* ph) {
  const SolverParams& p = scene.params;
  // Fluid particles are kept a quarter spacing inside the walls' boundary particles.
  const float inset = 0.25f * p.spacing;
  ph->domainMin = Vec3{scene.tank.min.x + inset, scene.tank.min.y + inset, scene.tank.min.z + inset};
  ph->domainMax = Vec3{scene.tank.max.x - inset, scene.tank.max.y - inset, scene.tank.max.z - inset};
  // Obstacles are sampled like the tank (a sheet half a spacing inside each face, fluid seeded half a
  // spacing outside): the same quarter-spacing inset, outward.
  ph->obstacleCount = static_cast<int>(std::min<size_t>(scene.obstacles.size(), kMaxObstacles));
  for (int k = 0; k < kMaxObstacles; ++k) {
    const bool used = k < ph->obstacleCount;
    const Aabb o = used ? scene.obstacles[k] : Aabb{};
    ph->obstacleMin[k] = used ? Vec3{o.min.x - inset, o.min.y - inset, o.min.z - inset} : Vec3{};
    ph->obstacleMax[k] = used ? Vec3{o.max.x + inset, o.max.y + inset, o.max.z + inset} : Vec3{};
  }
  ph->contactWidth = 0.1f * p.spacing;
  // Its potential at the clamp box stops a particle arriving at a quarter of the sound speed.
  ph->contactStrength = scene.wallContact && method.wallContact != ContactUse::kNone
                            ? 3.0f * ph->soundSpeed * ph->soundSpeed / (32.0f * ph->contactWidth)
                            : 0.0f;
  ph->contactBelowRestOnly = method.wallContact == ContactUse::kBelowRestDensity;
  ph->closedTop = !scene.openTop;
}

/// Spray, foam and bubbles (stages/diffuse.h), from the solver.diffuse_* keys.
DiffuseConstants DiffuseConstantsOf(const SolverParams& p) {
  DiffuseConstants d;
  d.enabled = p.diffuse > 0.0f;
  d.capacity = static_cast<int>(p.diffuseCapacity);
  d.trappedAir = p.diffuseTrappedAir;
  d.waveCrest = p.diffuseWaveCrest;
  d.trappedAirMin = p.diffuseTrappedAirMin;
  d.trappedAirMax = p.diffuseTrappedAirMax;
  d.waveCrestMin = p.diffuseWaveCrestMin;
  d.waveCrestMax = p.diffuseWaveCrestMax;
  d.energyMin = p.diffuseEnergyMin;
  d.energyMax = p.diffuseEnergyMax;
  d.lifetime = p.diffuseLifetime;
  d.buoyancy = p.diffuseBuoyancy;
  d.drag = p.diffuseDrag;
  d.sprayBelow = static_cast<int>(p.diffuseSprayBelow);
  d.bubbleAbove = static_cast<int>(p.diffuseBubbleAbove);
  d.radius = 0.5f * p.spacing;  // the fluid particle's radius
  return d;
}

}  // namespace

Physics MakePhysics(const SceneSetup& scene) {
  const SolverParams& p = scene.params;
  Physics ph;
  const float support = p.spacing * p.supportFactor;
  ph.kernel = CubicSpline::Make(support);
  ph.mass = p.restDensity * p.spacing * p.spacing * p.spacing;
  ph.restDensity = p.restDensity;
  ph.invRestDensity = 1.0f / p.restDensity;
  ph.boundaryGamma = WallDensityCorrection(ph.kernel, p.spacing, scene.boundaryLayers);
  ph.boundaryGradScale = WallGradientCorrection(ph.kernel, p.spacing, scene.boundaryLayers) / ph.boundaryGamma;
  // The models the method supports (its row of the solver table); the scene check warns about the rest.
  const SolverInfo& method = SolverInfoOf(scene.method);
  ph.wallDensity = scene.wallPressure == SceneSetup::WallPressure::kWallDensity && method.wallDensity;
  ph.maxNeighbours = NeighbourCapacity(p.supportFactor);
  // Moving bodies are one-sheet shells (interaction::SamplePaddle): their own flat-wall corrections.
  ph.bodyGradScale = WallGradientCorrection(ph.kernel, p.spacing, 1) / WallDensityCorrection(ph.kernel, p.spacing, 1);
  ph.bodyClearance = 0.25f * p.spacing;
  ph.continuityDensity = scene.density == DensityModel::kDeltaSph && method.deltaSph;
  SetReuseConstants(scene, method, &ph);
  ph.stiffness = p.stiffness;
  ph.exponent = p.exponent;
  ph.soundSpeed = std::sqrt(p.exponent * p.stiffness / p.restDensity);
  ph.smoothing = 0.5f * support;
  ph.alpha = p.viscosity;
  ph.gravity = scene.gravity;
  SetTankConstants(scene, method, &ph);
  ph.volume = ph.mass / p.restDensity;
  ph.diffuse = DiffuseConstantsOf(p);
  ph.step = 0;  // Solver::Step sets it
  return ph;
}

}  // namespace sphxr::sim
