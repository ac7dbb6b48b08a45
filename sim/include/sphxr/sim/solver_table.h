#pragma once
// The solver table: one row per pressure solver (`solver.method`). What each method is, what it
// supports, its stable time step, its statistics and its own rules (start-up warnings, parameters for a
// spacing) are read from here by the solver itself (which models it turns on), the scene check (which
// warnings), `--set`, the panel, `--quality auto`, the stats CSV and the generated scene reference;
// nothing outside a solver's own folder (sim/src/solvers/<method>/) and this table asks which method
// runs. Adding a solver: docs/dev/extending.md.
#include <cstdint>
#include <span>
#include <string>

#include "sphxr/sim/params.h"
#include "sphxr/sim/solve_report.h"

namespace sphxr::sim {

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
  /// Its stable step for the current state (solver.fixed_dt is clamped to it): under solver.max_dt for a
  /// method whose step follows the sound or the flow; PBF's is pbf_frame over pbf_substeps.
  float (*stableDt)(const StableDtInput& in);
  std::span<const SolveColumn> columns;  // its statistics (its SolveReport's fields), in the stats CSV's order
  /// Bytes of its own per fluid particle, given the neighbour-list slots per particle.
  int64_t (*bytesPerFluid)(int64_t neighbourSlots);
  /// The solver parameter (m/s) that its steps hold every particle's speed to, or nullptr: a scene's
  /// block faster than it is refused, as the start state the method would silently slow down.
  const char* speedCapParam;
  /// Its own start-up warnings about settings that run but will not give usable water (once, at
  /// Solver::Create; the table's flags above give the shared ones), or nullptr. `waterHeight`: m from
  /// the tank's floor to the highest block's top.
  void (*warnAtStart)(const SceneSetup& scene, float waterHeight);
  /// Its own parameters for a particle spacing (`--quality auto`): given the scene's parameters and a new
  /// `spacing`, sets in `*out` the ones of this method that follow the spacing and returns what it set,
  /// for a message ("" when nothing). nullptr: none of its parameters depends on the spacing.
  std::string (*paramsForSpacing)(const SolverParams& scene, float spacing, SolverParams* out);
  /// The margin (m) beyond the kernel's support that its neighbour lists keep so that they last several
  /// steps, or nullptr (lists every step): the grid's cells are the support plus this (MakeGridShape).
  float (*listMargin)(const SolverParams& params) = nullptr;
};

std::span<const SolverInfo> SolverTable();
const SolverInfo& SolverInfoOf(SolverMethod method);
/// The row named `name`, or nullptr.
const SolverInfo* FindSolver(const std::string& name);
/// "wcsph, dfsph, pbf" (help texts and errors).
std::string SolverNames();

}  // namespace sphxr::sim
