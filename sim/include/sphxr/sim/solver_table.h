#pragma once
// The solver table: one row per pressure solver (`solver.method`). What each method is, what it
// supports, its stable time step, its parameters and its statistics are read from here by the solver
// itself (which models it turns on), the scene check (which warnings), `--set`, the panel, `--quality
// auto`, the stats CSV and the generated scene reference; nothing outside a solver's own file and this
// table asks which method runs. Adding a solver: docs/dev/extending.md.
#include <cstdint>
#include <span>
#include <string>

#include "sphxr/sim/params.h"

namespace sphxr::sim {

struct StepInfo;

/// The values a solver may report of its step (StepInfo's solve fields), by stats-CSV column name.
enum class SolverStat { kDensityIterations, kDivergenceIterations, kDensityError, kDivergenceError };
const char* SolverStatName(SolverStat stat);  // "density_iterations", ...
double SolverStatValue(const StepInfo& info, SolverStat stat);

/// What the stable time step of a method reads.
struct StableDtInput {
  const SceneSetup& scene;
  float maxSpeed;  // m/s, of the last step (fluid or paddle, whichever is faster)
  float maxAccel;  // m/s^2, of the last step (gravity at least)
};

/// Which fluid particles the walls' contact (tank.wall_contact, stages/contact.h) acts on.
enum class ContactUse {
  kNone,
  kEveryParticle,
  /// Only particles lighter than rho0: the ones an implicit density solve cannot push (films, spray),
  /// so that its first layer of water at rest, which sits inside the contact zone, never carries it.
  kBelowRestDensity,
};

struct SolverInfo {
  SolverMethod method;
  const char* name;     // solver.method
  const char* paper;    // what it implements
  const char* summary;  // one line for the scene reference and the panel
  // The models it supports; a scene that asks for one it does not gets one warning and runs without it.
  bool wallDensity;  // tank.wall_pressure "wall_density" (docs/design/walls.md)
  bool deltaSph;     // solver.density "delta_sph"
  bool reuse;        // activity-based reuse (Huang et al. 2013, §3.3)
  ContactUse wallContact;  // tank.wall_contact (stages/contact.h)
  bool acoustic;     // its step and its compression follow the sound speed (the scene check's Mach warnings)
  /// Its stable step for the current state, solver.max_dt included (solver.fixed_dt is clamped to it).
  float (*stableDt)(const StableDtInput& in);
  std::span<const SolverStat> stats;  // what its steps report, in the stats CSV's order
  /// Its density solve may stop at solver.max_iterations short of its tolerance (then a warning).
  bool iterationCap;
  /// Bytes of its own per fluid particle, given the neighbour-list slots per particle.
  int64_t (*bytesPerFluid)(int64_t neighbourSlots);
  /// The solver parameter (m/s) that its steps hold every particle's speed to, or nullptr: a scene's
  /// block faster than it is refused, as the start state the method would silently slow down.
  const char* speedCapParam;
};

std::span<const SolverInfo> SolverTable();
const SolverInfo& SolverInfoOf(SolverMethod method);
/// The row named `name`, or nullptr.
const SolverInfo* FindSolver(const std::string& name);
/// "wcsph, dfsph, pbf" (help texts and errors).
std::string SolverNames();

}  // namespace sphxr::sim
