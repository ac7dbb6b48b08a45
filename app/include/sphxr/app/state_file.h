#pragma once
// State files: the fluid and the clock of a run, to restart from (`sphxr --save-state FILE`,
// `--load-state FILE`; docs/user/scenes.md "State files"). Every field of the one field list
// (sim/fields.h) is stored with its name and element size, so a file from a build with other fields
// is refused by name instead of being misread. Binary, little-endian, version 4 (read too: version 3
// lacks the diffuse particles, version 2 also the method, version 1 also the step count):
//
//   "SPHXRST1"  u32 0x01020304 (byte order)  u32 version
//   f64 time  f32 last max speed  f32 last max |a|  i64 step  f32 spacing  i32 fluid  i32 boundary
//   u32 n + n bytes: the scene's name   u32 n + n bytes: the solver method (a name of sim::SolverTable())
//   u32 bodies; per body: pose, from, to (7 f32 each: position x y z, orientation w x y z),
//     f64 fromTime, f64 toTime, 3 f32 velocity, 3 f32 angular velocity (sim::BodyMotionState)
//   u32 paddles; per paddle: i32 mode, 7 f32 commanded pose, 3+3+3 f32 force, torque, raw force,
//     f32 haptic, i64 teleports, u8 lost, f64 lostSince, f64 lastFrame (interaction::PaddleRestart);
//     then f64 the next frame's time (the paddle clock: app::Simulation::NextFrame)
//   u32 fields; per field: u32 n + n bytes of name, u32 element bytes, fluid x element bytes
//   u32 diffuse particles d; d Vec4 positions (w: lifetime left), d Vec4 velocities (w: kind), oldest
//     first (sim::HostDiffuse)
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct StateFile {
  sim::HostFluid fluid;
  sim::HostDiffuse diffuse;  // spray, foam and bubbles (empty in files before version 4)
  sim::SolverClock clock;
  /// Steps from the saved run's t = 0 (its first run's step 0, across continued runs), so that a run
  /// continued from the file numbers its steps, exports and CSV rows on as the whole run would; -1:
  /// unknown (a version-1 file, or a run continued from one; such a run numbers from 0).
  int64_t step = 0;
  float spacing = 0.0f;
  int fluidCount = 0;
  int boundaryCount = 0;
  std::string scene;  // the name of the scene it was saved from (informational)
  sim::SolverMethod method = sim::SolverMethod::kWcsph;  // the solver it ran under
  std::string path;   // the file it was read from (for messages)
  std::vector<sim::BodyMotionState> bodies;        // the moving bodies' (paddles') motion
  std::vector<interaction::PaddleRestart> paddles;  // the paddle system's own state (may be empty)
  double paddleClock = 0.0;                         // the next paddle frame's time (with `paddles`)
};

/// Writes the solver's fluid and clock to `path`, through `path.tmp` and a rename, so that a failed
/// write leaves any earlier file at `path` as it was.
/// With `paddles`, their own state and `paddleClock` (the runner's next paddle frame) are saved too, so
/// that a restart continues their motion exactly. The step count saved is `stepsBefore` (the steps
/// before this solver's first: a continued run's StateFile::step) plus the solver's own; a negative
/// `stepsBefore` (unknown) saves -1.
Status WriteStateFile(const std::string& path, const sim::Solver& solver, const std::string& sceneName,
                      const interaction::PaddleSystem* paddles = nullptr, double paddleClock = 0.0,
                      int64_t stepsBefore = 0);
/// Reads a state file; a one-line error names the path and what is wrong (not a state file, another
/// version or byte order, a field this build does not have or lacks, truncated).
Status ReadStateFile(const std::string& path, StateFile* out);
/// The same for the bytes of a file (`path` names it in messages): what ReadStateFile does once the
/// file is read, and what the fuzz target drives.
Status ParseStateFile(std::vector<char> data, const std::string& path, StateFile* out);
/// `--load-state path` for every mode: reads the file, refuses a `spacingOption` (--spacing, 0 when not
/// given) other than the file's, warns when it was saved from a scene of another name than `sceneName`,
/// and sets `setup`'s spacing to the file's. An empty path reads nothing.
Status ReadStartState(const std::string& path, float spacingOption, const std::string& sceneName,
                      sim::SceneSetup* setup, std::shared_ptr<const StateFile>* out);
/// Checks that `state` fits `solver` (the same fluid and boundary counts and spacing: the same scene at
/// the same spacing) and restores it (sim::Solver::Restore). With as many bodies as the file has, each
/// body's whole motion is restored; with fewer or more (the window and --xr add hand paddles after the
/// scene's) the first bodies are put at their saved poses, at rest, logged. Call before
/// interaction::PaddleSystem::Attach, which takes the bodies' poses as the paddles' commanded poses.
Status RestoreState(const StateFile& state, sim::Solver* solver);
/// After Attach: when the file has the paddle system's state for exactly these paddles (and bodies),
/// puts it back and sets `*paddleClock` to the saved next paddle frame (returns true); else changes
/// nothing (false): the paddles start from their bodies' poses.
bool RestorePaddles(const StateFile& state, const sim::Solver& solver, interaction::PaddleSystem* paddles,
                    double* paddleClock);

}  // namespace sphxr::app
