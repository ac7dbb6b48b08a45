#pragma once
// JSON scene files -> sim::SceneSetup. A scene declares only what it uses. Unknown keys are warned
// about by name; invalid values are refused with the key and the reason, before anything is allocated.
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "sphxr/app/probe_config.h"
#include "sphxr/common/status.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

/// The deepest nesting a scene file may have (no scene nests deeper than 6; the cap keeps every walk of
/// it shallow). The Python module refuses a deeper dict before turning it into text.
inline constexpr int kMaxSceneDepth = 64;

/// What the runner and the tests measure on a scene ("probe" section).
struct DamBreakProbe {
  float columnWidth = 0.0f;   // a, m: the column's width along x from the back wall
  float wallX = 0.0f;         // back wall
  float floorY = 0.0f;
  float depth = 0.0f;         // tank width along z (for the spray threshold)
};

/// The surge front and column height ignore spray: a bin one spacing wide belongs to the fluid body
/// only while it holds at least half a row of particles across the tank's depth (sim::ConnectedExtent).
inline int DamBreakMinPerBin(const DamBreakProbe& probe, float spacing) {
  return std::max(2, static_cast<int>(std::lround(0.5f * probe.depth / spacing)));
}

struct SceneFile {
  std::string path;
  std::string name;
  std::string description;
  sim::SceneSetup setup;
  double runTime = 0.0;       // s, default run length ("run.time")
  int64_t runSteps = 0;       // default step count ("run.steps"), used when runTime == 0
  double runSettle = 0.0;     // s of Solver::Settle before a headless run ("run.settle"; 0: none)
  std::optional<DamBreakProbe> damBreak;
  /// "paddles" section (absent: none). Scripted paddles carry their loaded trajectory.
  std::vector<interaction::PaddleDesc> paddles;
  double paddleFrameRate = 90.0;  // Hz: display frames at which the paddles get new targets
  std::optional<ProbeConfig> probes;  // "probes" section (docs/user/scenes.md#probes); absent: none
  std::optional<sim::SurfaceParams> surface;  // "surface" section (cell_size, iso_level, margin); absent: defaults
  std::vector<std::string> warnings;  // unknown keys, already logged
  std::vector<std::string> inputs;    // the other files it read (paddle trajectories)
};

/// Parses `text` (the content of a scene file). `origin` names it in messages.
Status ParseScene(const std::string& text, const std::string& origin, SceneFile* out);
/// Reads and parses a file.
Status LoadScene(const std::string& path, SceneFile* out);
/// Applies "key=value" to a solver parameter (the same names as the scene's "solver" section).
Status SetSolverParam(sim::SceneSetup* setup, const std::string& assignment);

/// The folders a scene given by name (`sphxr --scene stir`) is looked for in, in order: the current
/// directory, the installed scenes (<prefix>/share/sphxr/scenes beside <prefix>/bin/sphxr, found from
/// the running executable; `installDir` instead when given: the Python module's own prefix), or, when
/// there are none (a program run from its build tree), the source tree's scenes/ of the build. Those
/// that exist.
std::vector<std::string> SceneSearchDirs(const std::string& installDir = "");
/// `name` itself when it is a file or holds a '/'; else NAME or NAME.json in the first folder of
/// SceneSearchDirs(installDir) that has one. A bare name found nowhere is an error naming the folders.
Status FindScene(const std::string& name, std::string* path, const std::string& installDir = "");

}  // namespace sphxr::app
