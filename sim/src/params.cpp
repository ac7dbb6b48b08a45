#include <array>
#include <string>

#include "sampling.h"
#include "sphxr/sim/diffuse.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {
namespace {

const std::array<ParamInfo, 42> kParams = {{
    {"spacing", "m", "rest spacing of the fluid particles; mass = rest_density * spacing^3", 1e-4, 1.0,
     &SolverParams::spacing},
    {"support_factor", "", "kernel support radius in spacings (cubic spline); below 1.8 the rest lattice alone is over-dense", 1.8, 4.0, &SolverParams::supportFactor},
    {"rest_density", "kg/m^3", "density of the fluid at rest", 1.0, 1e5, &SolverParams::restDensity},
    {"stiffness", "Pa", "Tait stiffness B: p = B((rho/rho0)^gamma - 1); sound speed sqrt(gamma B / rho0)", 1.0, 1e10,
     &SolverParams::stiffness},
    {"exponent", "", "Tait exponent gamma", 1.0, 10.0, &SolverParams::exponent},
    {"viscosity", "", "Monaghan artificial viscosity alpha between fluid particles", 0.0, 10.0,
     &SolverParams::viscosity},
    {"boundary_viscosity", "", "artificial viscosity alpha between fluid and walls for tank.friction \"artificial\" (the default) and between fluid and paddles", 0.0, 10.0,
     &SolverParams::boundaryViscosity},
    {"cfl", "", "CFL number: dt <= cfl * h / (c + v_max)", 0.01, 1.0, &SolverParams::cfl},
    {"max_dt", "s", "upper bound of the time step", 1e-7, 0.1, &SolverParams::maxDt},
    {"fixed_dt", "s", "fixed time step (0 = adaptive); clamped to the stability limit", 0.0, 0.1,
     &SolverParams::fixedDt},
    {"density_tolerance", "%", "dfsph: the density solve stops at this mean compression", 1e-5, 10.0,
     &SolverParams::densityTolerance, false, "dfsph"},
    {"divergence_tolerance", "%", "dfsph: the divergence solve stops at this mean compression per step", 1e-5, 100.0,
     &SolverParams::divergenceTolerance, false, "dfsph"},
    {"min_iterations", "", "dfsph: density solve iterations at least", 0.0, 1000.0, &SolverParams::minIterations, true,
     "dfsph"},
    {"max_iterations", "", "dfsph: density solve iterations at most (reaching it is a warning; 0 = no density solve)", 0.0, 10000.0,
     &SolverParams::maxIterations, true, "dfsph"},
    {"min_divergence_iterations", "", "dfsph: divergence solve iterations at least (when it runs)", 0.0, 1000.0,
     &SolverParams::minDivergenceIterations, true, "dfsph"},
    {"max_divergence_iterations", "", "dfsph: divergence solve iterations at most (0 = no divergence solve)", 0.0,
     10000.0, &SolverParams::maxDivergenceIterations, true, "dfsph"},
    {"pbf_frame", "s", "pbf: the frame it substeps where no frame clock sets it (the sim library alone); a run of the app substeps the displayed frame, 1 / paddles.frame_rate, instead (pbf ignores max_dt and cfl)",
     1e-4, 0.1, &SolverParams::pbfFrame, false, "pbf"},
    {"pbf_iterations", "", "pbf: Jacobi iterations of the density constraint per step (the cost is fixed by it)", 1.0,
     100.0, &SolverParams::pbfIterations, true, "pbf"},
    {"pbf_substeps", "", "pbf: steps per pbf_frame", 1.0, 16.0,
     &SolverParams::pbfSubsteps, true, "pbf"},
    {"pbf_skin", "", "pbf: the neighbour lists' margin beyond the support, in spacings: the grid, the sort and the lists are built once per frame and again when a particle has moved half of it (0 = every step)",
     0.0, 2.0, &SolverParams::pbfSkin, false, "pbf"},
    {"pbf_relaxation", "", "pbf: constraint-force mixing epsilon, as a fraction of the rest lattice's sum of squared constraint gradients",
     1e-6, 10.0, &SolverParams::pbfRelaxation, false, "pbf"},
    {"pbf_corr_k", "", "pbf: artificial pressure s_corr = -k (W(r)/W(dq))^n against clumping at the surface (0 = off)",
     0.0, 1.0, &SolverParams::pbfCorrK, false, "pbf"},
    {"pbf_corr_n", "", "pbf: the artificial pressure's exponent n", 1.0, 8.0, &SolverParams::pbfCorrN, true, "pbf"},
    {"pbf_corr_dq", "", "pbf: the artificial pressure's dq, in kernel support radii", 0.01, 0.9, &SolverParams::pbfCorrDq,
     false, "pbf"},
    {"pbf_xsph", "", "pbf: XSPH viscosity c (0 = none)", 0.0, 1.0, &SolverParams::pbfXsph, false, "pbf"},
    {"pbf_vorticity", "m/s", "pbf: vorticity confinement epsilon: the acceleration eps (N x omega), N toward the vortices' cores (0 = off)",
     0.0, 10.0, &SolverParams::pbfVorticity, false, "pbf"},
    {"pbf_max_speed", "m/s", "pbf: speeds are capped here (a safety net against a runaway correction)", 0.01, 1000.0,
     &SolverParams::pbfMaxSpeed, false, "pbf"},
    {"diffuse", "", "1: spray, foam and air bubbles (Ihmsen et al. 2012) spawned and moved after every step; they never act on the water (0 = off)",
     0.0, 1.0, &SolverParams::diffuse, true},
    {"diffuse_capacity", "", "diffuse particles at most (the pool, allocated once); when full the oldest are retired first",
     1.0, 1e8, &SolverParams::diffuseCapacity, true},
    {"diffuse_trapped_air", "1/s", "k_ta: diffuse particles a fluid particle spawns per second at full trapped-air and kinetic-energy potentials",
     0.0, 1e7, &SolverParams::diffuseTrappedAir},
    {"diffuse_wave_crest", "1/s", "k_wc: the same at full wave-crest and kinetic-energy potentials", 0.0, 1e7,
     &SolverParams::diffuseWaveCrest},
    {"diffuse_trapped_air_min", "m/s", "tau_ta min: the trapped-air potential (neighbours' relative speed toward each other, weighted) is 0 below it",
     0.0, 1e4, &SolverParams::diffuseTrappedAirMin},
    {"diffuse_trapped_air_max", "m/s", "tau_ta max: the trapped-air potential is 1 above it", 0.0, 1e4,
     &SolverParams::diffuseTrappedAirMax},
    {"diffuse_wave_crest_min", "", "tau_wc min: the wave-crest potential (surface curvature where the water moves along its normal) is 0 below it",
     0.0, 1e4, &SolverParams::diffuseWaveCrestMin},
    {"diffuse_wave_crest_max", "", "tau_wc max: the wave-crest potential is 1 above it", 0.0, 1e4,
     &SolverParams::diffuseWaveCrestMax},
    {"diffuse_energy_min", "J/kg", "tau_k min: a fluid particle with less kinetic energy (1/2 v^2) spawns nothing", 0.0, 1e6,
     &SolverParams::diffuseEnergyMin},
    {"diffuse_energy_max", "J/kg", "tau_k max: the kinetic-energy potential is 1 above it", 0.0, 1e6,
     &SolverParams::diffuseEnergyMax},
    {"diffuse_lifetime", "s", "the longest a foam particle lives (each draws 0.5 to 1 of it; spray and bubbles do not age)",
     1e-3, 1e4, &SolverParams::diffuseLifetime},
    {"diffuse_buoyancy", "", "k_b: an air bubble's buoyancy, in units of gravity", 0.0, 100.0, &SolverParams::diffuseBuoyancy},
    {"diffuse_drag", "", "k_d: the share of an air bubble's velocity difference to the water that drag removes per step",
     0.0, 1.0, &SolverParams::diffuseDrag},
    {"diffuse_spray_below", "", "a diffuse particle with fewer fluid neighbours (within the kernel support) is spray",
     0.0, 1000.0, &SolverParams::diffuseSprayBelow, true},
    {"diffuse_bubble_above", "", "a diffuse particle with more fluid neighbours is an air bubble; between the two, foam",
     0.0, 1000.0, &SolverParams::diffuseBubbleAbove, true},
}};

const std::array<ReuseParamInfo, 6> kReuseParams = {{
    {"delta1", "", "weight of the pressure term delta1 P_i / P_pc in ACT_i (Huang et al. 2013, 3.3)", 0.0, 1e9,
     &ReuseParams::delta1},
    {"delta2", "", "weight of the crowding term delta2 N_CPN / N_i in ACT_i", 0.0, 1e9, &ReuseParams::delta2},
    {"threshold", "", "ACT_i below this makes a particle inactive (it reuses its values)", 0.0, 1e9,
     &ReuseParams::threshold},
    {"pressure_scale", "Pa", "P_pc; 0 = the Tait pressure at 1 % compression", 0.0, 1e9, &ReuseParams::pressureScale},
    {"cell_count", "", "N_CPN; 0 = the rest lattice's particles per cell", 0.0, 1e9, &ReuseParams::cellCount},
    {"idle", "steps", "IDLE: consecutive steps an inactive particle reuses its density, pressure and acceleration", 0.0,
     1000.0, nullptr, &ReuseParams::idle},
}};

}  // namespace

std::span<const ParamInfo> SolverParamInfos() { return kParams; }

std::span<const SceneLimitInfo> SceneLimits() {
  static constexpr SceneLimitInfo kLimits[] = {
      {"fluid", kMaxFluidBlocks, "blocks; overlaps are found on a grid of about one cell per block"},
      {"obstacles", kMaxObstacles, "boxes; every step checks each fluid particle against each"},
      {"paddles.list", kMaxBodies, "paddles (moving bodies)"},
      {"paddles.list[].shapes", kMaxBodyShapes, "boxes and capsules of one paddle; every step's contact test loops over them"},
      {"probes", kMaxProbes, "pressure, level and force probes together (a CSV column each, six for a force)"},
  };
  return kLimits;
}
std::span<const ReuseParamInfo> ReuseParamInfos() { return kReuseParams; }

float WallFrictionAlpha(const SolverParams& params, WallFriction friction) {
  switch (friction) {
    case WallFriction::kArtificial: return params.boundaryViscosity;
    case WallFriction::kNoSlip: return 4.0f * params.viscosity;
    case WallFriction::kFreeSlip: return 0.0f;
  }
  return params.boundaryViscosity;
}

const char* WallFrictionName(WallFriction friction) {
  switch (friction) {
    case WallFriction::kArtificial: return "artificial";
    case WallFriction::kNoSlip: return "no_slip";
    case WallFriction::kFreeSlip: return "free_slip";
  }
  return "artificial";
}

const char* DiffuseKindName(DiffuseKind kind) {
  switch (kind) {
    case DiffuseKind::kSpray: return "spray";
    case DiffuseKind::kFoam: return "foam";
    case DiffuseKind::kBubble: return "bubble";
  }
  return "?";
}

const char* DensityModelName(DensityModel model) {
  return model == DensityModel::kDeltaSph ? "delta_sph" : "summation";
}

bool ParseDensityModel(const std::string& text, DensityModel* out) {
  if (text == "summation") *out = DensityModel::kSummation;
  else if (text == "delta_sph") *out = DensityModel::kDeltaSph;
  else return false;
  return true;
}

const ParamInfo* FindSolverParam(const std::string& key) {
  for (const ParamInfo& p : kParams) {
    if (key == p.key) return &p;
  }
  return nullptr;
}

ParticleCounts CountParticles(const SceneSetup& scene) {
  ParticleCounts c;
  c.fluid = SampleFluid(scene, nullptr);
  c.boundary = SampleBoundary(scene, nullptr);
  c.gridCells = MakeGridShape(scene).Cells();
  c.neighbourSlots = NeighbourCapacity(scene.params.supportFactor);
  for (const RigidBodySetup& b : scene.bodies) c.bodyParticles += static_cast<int64_t>(b.points.size());
  c.reuse = scene.reuse.enabled;
  c.wallDensity = scene.wallPressure == SceneSetup::WallPressure::kWallDensity;
  c.solverBytesPerFluid = SolverInfoOf(scene.method).bytesPerFluid(c.neighbourSlots);
  c.diffuseCapacity = scene.params.diffuse > 0.0f ? static_cast<int64_t>(scene.params.diffuseCapacity) : 0;
  return c;
}

int64_t EstimateMemoryBytes(const ParticleCounts& counts) {
  // sim/src/backend_impl.h's members. Fluid: the field list (68 B) + sort keys and order (8) + reorder
  // scratch of each element type (16 + 4 + 4 + 4) + the sort's temporary storage (about keys and values
  // again, 8) + the CPU density stage's block starts (4) + the host copy at creation (68). Neighbour
  // lists: 4 B per slot and a count (sim/src/stages.h NeighbourList). Reuse: the compacted list (4), the
  // CPU density blocks' keys of it and every particle's rank in it (8; counted for CUDA too, erring high);
  // bodies: each fluid particle's pressure term for the reaction (4). Boundary: 16 B, plus its sort at
  // start-up (~40 B transient) and the host copy (16); with wall_density its pressure term (4). Grid:
  // 4 ranges of 4 B and the near-boundary flag per cell; with bodies their 2 ranges and near flag (9),
  // with wall_density the wall-cell list's first size (4), with reuse the cells' counts and crowding (8). Bodies'
  // own particles: body frame, index and alpha (24), sorted world copies of position, velocity and
  // force (48), keys, order and owner (12). The pressure solver's own arrays: its row of the solver table.
  // Diffuse particles (diffuse_pool.h): per fluid particle the sort's keys and order, the sorted copies of
  // position, velocity and id, the normal, the spawn counts and their sums, the sort's storage (8 + 36 +
  // 16 + 8 + 8); per cell two ranges and a flag (9); per pool slot two buffers of position and velocity, alive and rank (72).
  const bool diffuse = counts.diffuseCapacity > 0;
  const int64_t perFluid = 68 + 8 + 28 + 8 + 4 + 68 + 4 * counts.neighbourSlots + 4 + (counts.reuse ? 12 : 0) +
                           (counts.bodyParticles > 0 ? 4 : 0) + (diffuse ? 76 : 0) +
                           counts.solverBytesPerFluid;
  const int64_t perBoundary = 16 + 40 + 16 + (counts.wallDensity ? 4 : 0);
  const int64_t perCell = 17 + (counts.bodyParticles > 0 ? 9 : 0) + (counts.wallDensity ? 4 : 0) + (counts.reuse ? 8 : 0) +
                          (diffuse ? 9 : 0);
  return counts.fluid * perFluid + counts.boundary * perBoundary + counts.gridCells * perCell +
         counts.bodyParticles * (24 + 48 + 12) + counts.diffuseCapacity * 72;
}

}  // namespace sphxr::sim

namespace sphxr::sim {

// The presets, chosen from the sweep in docs/design/impulse_hold.md (bench/reuse.cpp).
// `balanced`: delta1 0 makes the classification the 27-cell crowding alone, so a cell's particles are
// classified alike; T 1.5 keeps the free surface active (its crowding term is about 1.5); IDLE 3 is
// the stable limit (IDLE 5 blew up both scenes). Deep tank 2.45x, dam_break_1m 1.78x by wall time.
// `accurate`: IDLE 1, the smallest deviation measured (surge front 0.15 %).
// `fast`: T 1.8, so calm parts of the free surface reuse too.
bool ApplyReusePreset(const std::string& name, ReuseParams* reuse) {
  struct Preset {
    const char* name;
    float delta1, delta2, threshold;
    int idle;
  };
  static const Preset kPresets[] = {
      {"accurate", 0.1f, 1.0f, 1.6f, 1},
      {"balanced", 0.0f, 1.0f, 1.5f, 3},
      {"fast", 0.0f, 1.0f, 1.8f, 3},
  };
  for (const Preset& p : kPresets) {
    if (name != p.name) continue;
    reuse->enabled = true;
    reuse->delta1 = p.delta1;
    reuse->delta2 = p.delta2;
    reuse->threshold = p.threshold;
    reuse->idle = p.idle;
    return true;
  }
  return false;
}

const char* ReusePresetNames() { return "accurate, balanced, fast"; }

}  // namespace sphxr::sim
