#pragma once
// What the solver needs to know about a scene, as plain data. The JSON scene loader (app/) fills
// these structs; the solver validates them again (sim never trusts its caller with physics).
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sphxr/sim/rigid.h"
#include "sphxr/sim/vec.h"

namespace sphxr::sim {

/// Scalar solver parameters. Every one is described once in SolverParamInfos() (name, unit, range,
/// help), and that table drives the scene file, the command line and validation.
struct SolverParams {
  float spacing = 0.02f;           // m, rest particle spacing dx; particle mass = rho0 * dx^3
  float supportFactor = 2.0f;      // kernel support radius / spacing
  float restDensity = 1000.0f;     // kg/m^3
  float stiffness = 50000.0f;      // Pa, Tait B (Becker & Teschner 2007, eq. 7)
  float exponent = 7.0f;           // Tait gamma
  float viscosity = 0.02f;         // Monaghan artificial viscosity alpha, fluid-fluid
  float boundaryViscosity = 0.02f; // alpha between fluid and walls (wall friction)
  float cfl = 0.4f;                // CFL number for the adaptive time step
  float maxDt = 2e-3f;             // s, upper bound of the adaptive step
  float fixedDt = 0.0f;            // s, 0 = adaptive; a fixed step above the CFL limit is clamped
  // dfsph (Bender & Koschier 2017): the solves' stopping rules; SPlisHSPlasH's defaults.
  float densityTolerance = 0.02f;    // %, mean compression at which the density solve stops (bench/dfsph_step.sh)
  float divergenceTolerance = 0.1f;  // %, mean compression rate (per step) at which the divergence solve stops
  float minIterations = 2.0f;        // density solve iterations at least
  float maxIterations = 100.0f;      // density solve iterations at most (then a warning)
  float minDivergenceIterations = 0.0f;   // divergence solve iterations at least (when it runs)
  float maxDivergenceIterations = 100.0f;  // divergence solve iterations at most
  // pbf (Macklin & Müller 2013): the constraint solve and its corrections (docs/design/pbf.md says why
  // these values: the least work that holds a 20-spacing column at rest at 90 Hz).
  float pbfFrame = 1.0f / 90.0f; // s: the frame it substeps (app::Simulation sets it to the displayed frame)
  float pbfIterations = 3.0f;    // Jacobi iterations of the density constraint per step
  float pbfSubsteps = 3.0f;      // steps per pbf_frame
  float pbfSkin = 0.0f;          // spacings: the neighbour lists' margin beyond the support (0: lists every step)
  float pbfRelaxation = 1.0f;    // constraint-force mixing epsilon, relative to the rest lattice's sum |grad C|^2
  float pbfCorrK = 0.1f;         // artificial pressure s_corr = -k (W(r) / W(dq))^n
  float pbfCorrN = 4.0f;
  float pbfCorrDq = 0.2f;        // dq in kernel support radii
  float pbfXsph = 0.01f;         // XSPH viscosity c
  float pbfVorticity = 0.0f;     // m/s: vorticity confinement epsilon (0 = off; docs/design/pbf.md)
  float pbfMaxSpeed = 20.0f;     // m/s, the velocity cap (a safety net)
  // Diffuse particles: spray, foam and bubbles (Ihmsen et al. 2012, sphxr/sim/diffuse.h): the paper's
  // potentials' ranges and rates; docs/design/diffuse.md says why and what the shipped scenes set.
  float diffuse = 0.0f;                 // 1: spawned and moved after every step (they never act on the water)
  float diffuseCapacity = 65536.0f;     // the pool's size; when full the oldest are retired first
  float diffuseTrappedAir = 4000.0f;    // k_ta, per second
  float diffuseWaveCrest = 50000.0f;    // k_wc, per second
  float diffuseTrappedAirMin = 5.0f;    // tau_ta, m/s
  float diffuseTrappedAirMax = 20.0f;
  float diffuseWaveCrestMin = 2.0f;     // tau_wc
  float diffuseWaveCrestMax = 8.0f;
  float diffuseEnergyMin = 5.0f;        // tau_k, J/kg
  float diffuseEnergyMax = 50.0f;
  float diffuseLifetime = 5.0f;         // s, the longest a foam particle lives (each draws 0.5-1 of it)
  float diffuseBuoyancy = 2.0f;         // k_b
  float diffuseDrag = 0.8f;             // k_d
  float diffuseSprayBelow = 6.0f;       // fluid neighbours: fewer is spray
  float diffuseBubbleAbove = 20.0f;     // more is an air bubble
};

/// The pressure solver (`solver.method` in a scene, a name, never a number).
enum class SolverMethod {
  kWcsph,  // weakly compressible SPH, Tait equation of state (Becker & Teschner 2007): the paper's
  kDfsph,  // divergence-free SPH (Bender & Koschier 2015, 2017): a step set by the flow speed
  kPbf,    // position-based fluids (Macklin & Müller 2013): a fixed cost per displayed frame
};
/// The method's name in its row of the solver table (sphxr/sim/solver_table.h).
const char* SolverMethodName(SolverMethod method);
/// Parses a row's name ("wcsph", "dfsph", "pbf").
bool ParseSolverMethod(const std::string& text, SolverMethod* out);

/// How WCSPH finds each particle's density (`solver.density`, a name). kSummation: rho_i = sum_j m W_ij
/// every step (Becker & Teschner 2007). kDeltaSph: density is integrated state, the continuity equation
/// with the delta-SPH diffusion term (Molteni & Colagrossi 2009, Antuono et al. 2010) and the hydrostatic
/// correction of Fourtakas et al. (2019), meant to give a pressure field without the summation's
/// flicker (docs/dev/physics.md; sim/src/stages/density_diffusion.h). DFSPH always sums; reuse needs the summation.
enum class DensityModel { kSummation, kDeltaSph };
const char* DensityModelName(DensityModel model);
/// Parses "summation" | "delta_sph".
bool ParseDensityModel(const std::string& text, DensityModel* out);

struct ParamInfo {
  const char* key;    // scene-file key and command-line name
  const char* unit;
  const char* help;
  double min, max;    // inclusive valid range
  float SolverParams::*member;
  bool integer = false;  // a count (iterations): whole numbers only
  /// The solver it belongs to (its row of the solver table: the panel shows it with that method, the
  /// scene check warns when it is set under another); nullptr: every solver reads it.
  const char* method = nullptr;
};

/// The table of solver parameters (same order as SolverParams).
std::span<const ParamInfo> SolverParamInfos();
const ParamInfo* FindSolverParam(const std::string& key);

/// Where a fluid particle can be clamped back into the water (Totals::clampedAt): the tank's six faces
/// (x-, x+, floor, top, z-, z+), then each obstacle. A scene has at most kMaxObstacles obstacles.
inline constexpr int kTankFaces = 6;
inline constexpr int kMaxObstacles = 16;
inline constexpr int kClampSites = kTankFaces + kMaxObstacles;

/// The counts a scene may hold. The scene reader refuses a list longer than its limit before it reads
/// one item of it, and every check of a scene is linear (or n log n) up to these counts.
inline constexpr int kMaxFluidBlocks = 100000;  // checked for overlaps on a grid, in linear time
inline constexpr int kMaxBodies = 64;           // moving bodies (paddles): each is a solid the step integrates
inline constexpr int kMaxBodyShapes = 256;      // a body's boxes and capsules: each step's contact tests loop over them
inline constexpr int kMaxProbes = 1024;         // pressure, level and force probes together: a CSV column each
/// A row of limits for the scene reference (docs/user/scenes.md "Limits").
struct SceneLimitInfo {
  const char* key;
  int limit;
  const char* why;
};
std::span<const SceneLimitInfo> SceneLimits();

struct FluidBlock {
  Aabb box;
  Vec3 velocity;  // initial velocity, m/s
  /// Start in hydrostatic equilibrium: each layer is compressed to the Tait density of its depth below
  /// the block's top, the lowest layer staying where the plain lattice has it (the surface comes down),
  /// so a pool starts at rest instead of ringing from a zero-pressure lattice.
  bool hydrostatic = false;
};

/// Activity-based property reuse (Huang et al. 2013, section 3.3): ACT_i = delta1 P_i / P_pc +
/// delta2 N_CPN / N_i with P_i the previous step's pressure and N_i the mean particle count of the 27
/// cells around i; ACT_i < threshold makes i inactive for `idle` steps, in which it keeps its density,
/// pressure and acceleration. Disabled, the step is exactly the plain WCSPH step.
/// How a particle that reuses moves: the impulse hold (docs/design/impulse_hold.md). A particle goes
/// inactive only on steps whose number is a multiple of IDLE + 1 (the synchronised schedule), takes the
/// kick of all its IDLE + 1 steps, (IDLE + 1) dt a, on the step it computes, and drifts at that velocity
/// while it reuses; measured stable to IDLE 3 at the CFL step (IDLE 5 blew up).
struct ReuseParams {
  bool enabled = false;
  float delta1 = 1.0f;
  float delta2 = 1.0f;
  float threshold = 1.2f;
  int idle = 3;                  // IDLE: consecutive steps a particle reuses its values
  float pressureScale = 0.0f;    // P_pc, Pa; 0 = the Tait pressure at 1 % compression
  float cellCount = 0.0f;        // N_CPN; 0 = (cell size / spacing)^3, the rest lattice's count
};

/// One parameter of the scene's "reuse" section, described once like SolverParamInfos(): the scene
/// file, --set, the panel and validation read it. Exactly one of `real` and `count` is set.
struct ReuseParamInfo {
  const char* key;   // inside the section: "threshold" (the scene's "reuse.threshold")
  const char* unit;
  const char* help;
  double min, max;   // inclusive valid range
  float ReuseParams::*real = nullptr;
  int ReuseParams::*count = nullptr;  // a whole number
};
/// The table of reuse parameters (the scene reference's order; `enabled` is the section's presence).
std::span<const ReuseParamInfo> ReuseParamInfos();

/// The presets chosen from the measured trade (docs/design/impulse_hold.md): "accurate", "balanced", "fast".
/// Each sets delta1, delta2, threshold and idle and turns reuse on; the derived constants
/// (pressure_scale, cell_count) are left as they are. False for an unknown name.
bool ApplyReusePreset(const std::string& name, ReuseParams* reuse);
/// The preset names, for help texts and errors: "accurate, balanced, fast".
const char* ReusePresetNames();

/// How a wall drags on the water moving along it (docs/design/walls.md#friction).
/// kArtificial: the artificial viscosity alpha = solver.boundary_viscosity between fluid and wall, with
/// the wall at rest (Akinci et al. 2012, eq. 11). kNoSlip: the fluid's own viscosity (solver.viscosity)
/// and a no-slip wall: the fluid's pair term with each wall particle as a fluid particle of mass Psi_b
/// moving at the mirror image -v_i of the particle's velocity, so the velocity interpolated to the face,
/// halfway between the first fluid layer and the first wall sheet, is zero (Morris et al. 1997); no
/// constant is chosen. kFreeSlip: no viscous term (the wall holds the water only along its normal).
enum class WallFriction : uint8_t { kArtificial, kNoSlip, kFreeSlip };

/// The friction of each face of the tank, and of the obstacles.
struct TankFriction {
  WallFriction floor = WallFriction::kArtificial;  // y min
  WallFriction top = WallFriction::kArtificial;    // y max (a closed tank's lid)
  WallFriction xMin = WallFriction::kArtificial, xMax = WallFriction::kArtificial;
  WallFriction zMin = WallFriction::kArtificial, zMax = WallFriction::kArtificial;
  WallFriction obstacles = WallFriction::kArtificial;
};

/// The viscosity coefficient of a wall particle's term in the force stage (the boundaryAlpha of
/// stages/forces.h) for a wall of this friction: boundary_viscosity, 4 x viscosity (twice for the fluid
/// pair term's mass form, twice for the mirrored relative velocity 2 v_i), or 0.
float WallFrictionAlpha(const SolverParams& params, WallFriction friction);
/// "artificial", "no_slip", "free_slip".
const char* WallFrictionName(WallFriction friction);

struct SceneSetup {
  SolverParams params;
  SolverMethod method = SolverMethod::kWcsph;
  DensityModel density = DensityModel::kSummation;
  Vec3 gravity{0.0f, -9.81f, 0.0f};
  /// The tank: its interior is the simulation domain. Walls and floor are sampled as boundary
  /// particles on its faces (the top face only when `openTop` is false).
  Aabb tank{{0, 0, 0}, {1, 1, 1}};
  bool openTop = true;
  /// How each tank face and the obstacles drag on the water along them (`tank.friction`,
  /// docs/design/walls.md#friction). Every face kArtificial by default.
  TankFriction friction;
  int boundaryLayers = 1;        // layers of boundary particles behind each wall
  /// How a wall particle's pressure is found (docs/design/walls.md). kMirrored: p_b = the fluid
  /// particle's own pressure (at least its neighbours' Shepard average); matches Martin & Moyce, but
  /// is not the derivative of an energy and keeps still water circulating at ~1 cm/s. kWallDensity:
  /// each wall particle's own density from the fluid around it; energy-consistent, still water comes
  /// to rest and meets hydrostatics within 3 %, but the dam break's column height at the back wall is
  /// +14 % against Martin & Moyce (mirrored: +8.8 %, through a dip at the wall; physics.md).
  enum class WallPressure { kMirrored, kWallDensity };
  WallPressure wallPressure = WallPressure::kMirrored;
  /// A short-range contact force from the tank's faces and the obstacles on water the boundary
  /// particles do not hold (pressure-free films and spray; stages/contact.h). false: the boundary
  /// particles and the clamp alone.
  bool wallContact = true;
  std::vector<FluidBlock> fluid;
  std::vector<Aabb> obstacles;   // solid boxes inside the tank, surfaces sampled
  ReuseParams reuse;             // no "reuse" section in the scene: disabled
  /// Kinematic rigid bodies (paddles) moving through the fluid; fluid is not seeded inside them.
  std::vector<RigidBodySetup> bodies;
};

/// Counts the particles a scene will create, without allocating them (for validation).
struct ParticleCounts {
  int64_t fluid = 0;
  int64_t boundary = 0;
  int64_t gridCells = 0;
  int64_t neighbourSlots = 0;  // per fluid particle (4 bytes each)
  int64_t bodyParticles = 0;   // of the moving bodies (paddles)
  bool reuse = false;          // the compacted list of computing particles, the cells' crowding
  bool wallDensity = false;    // the walls' own pressure and the list of wall cells
  int64_t solverBytesPerFluid = 0;  // the pressure solver's own arrays (SolverInfo::bytesPerFluid)
  int64_t diffuseCapacity = 0;      // the diffuse particles' pool (0: off)
};
ParticleCounts CountParticles(const SceneSetup& scene);

/// Bytes the solver allocates for a scene of these counts (used to refuse scenes that do not fit).
int64_t EstimateMemoryBytes(const ParticleCounts& counts);

}  // namespace sphxr::sim
