#pragma once
// The command line of every mode (`sphxr --help`): the options, their parsing, and what every mode does
// with them before it runs (the scene with the command line's changes, the state file, the solver's
// threads, --quality auto). main.cpp picks the mode; headless.h, desktop.h and xr_mode.h run one.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sphxr/app/scene_file.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct StateFile;

enum class Mode { kAuto, kHeadless, kDesktop, kXr };

struct Options {
  Mode mode = Mode::kAuto;
  std::string scenePath;
  double time = 0.0;        // s; 0 = the scene's run.time (or run.steps)
  int64_t steps = 0;        // 0 = use time
  std::string loadState;    // --load-state: the run starts from this state file (state_file.h)
  std::string saveState;    // --save-state: the state at the end of the run (also when stopped early)
  double checkpointEvery = 0.0;  // --checkpoint-every: simulated s between saves of saveState during the run (0: none)
  int checkpointKeep = 2;        // --checkpoint-keep: checkpoints kept (saveState, saveState.1, ...)
  double settle = -1.0;     // s of Solver::Settle before the run; -1 = the scene's run.settle, 0 = none
  sim::Device device = sim::Device::kAuto;
  int threads = 0;          // 0 = all cores
  float spacing = 0.0f;     // m; 0 = the scene's spacing
  int64_t exportEvery = 0;  // steps between particle exports (0 = none)
  std::string outDir = "out";
  std::string exportFormat = "ply";  // ply | vtk
  int64_t exportSurfaceEvery = 0;    // steps between surface exports (0 = none), into outDir
  std::string surfaceFormat = "ply"; // ply | obj
  std::string statsPath;    // per-step CSV
  std::string probesPath;   // --probes: the scene's probes, a row every probes.every s (probe_csv.h)
  double exportInterval = 0.0;         // --export-interval: simulated s between particle exports (0 = none)
  double exportSurfaceInterval = 0.0;  // --export-surface-interval: the same for the surface
  bool validate = false;
  int reuse = -1;           // -1 = as the scene says, 0 = off, 1 = on (the scene's or default parameters)
  std::string reusePreset;  // --reuse accurate|balanced|fast: that preset (turns reuse on)
  std::vector<std::string> sets;  // solver parameter overrides "key=value"
  int progress = -1;        // -1 = when stderr is a terminal
  // Pictures without a display (EGL): a PNG of the last state, and/or a PNG every 1/fps simulated s.
  std::string screenshotPath;
  std::string framesDir;
  double fps = 30.0;
  int imageWidth = 1280, imageHeight = 720;
  bool particleImages = false;  // --render particles: coloured particles instead of water
  // Desktop window.
  int windowWidth = 1280, windowHeight = 720;
  int frameLimit = 0;           // close the window after this many frames (0 = when the user closes it)
  bool vsync = true;
  bool glDebug = false;         // --gl-debug: GL debug callback on in a release build (any GL error aborts)
  int quality = -1;             // --quality: -1 = auto in the desktop window, scene headless; 0 = scene; 1 = auto
  std::string renderQuality = "high";  // --render-quality: where the window's and the headset's drawing starts
  std::string frameStatsPath;   // --frame-stats: one CSV row per displayed frame (window, headset)
  bool help = false;
  bool printSceneReference = false;  // --print-scene-reference: print SceneParameterReference() and exit
};

/// Parses argv. Values are checked here (a bad number is a one-line error naming the flag).
Status ParseCommandLine(int argc, const char* const* argv, Options* out);
std::string UsageText();

/// Loads options.scenePath and applies the command line's changes to it, in the order every mode uses:
/// a --reuse preset replaces the scene's reuse parameters, then each --set, then --spacing, then
/// --reuse on|off. The headless runner, the desktop window and --xr all start from this.
Status LoadSceneWithOptions(const Options& options, SceneFile* scene);

/// The options given that only a headless run honours (--stats, --export-every, --export-surface-every,
/// --time, --steps, --settle), e.g. "--stats, --time"; empty when none. The desktop window and --xr warn
/// with it once their window is open (a fallback to headless still honours them). --save-state is not
/// one: every mode writes its file (the window's and the headset's saves).
std::string HeadlessOnlyOptions(const Options& options);
/// The spacing the command line asks for (--spacing, else --set spacing=...), 0 when it asks for none.
float ExplicitSpacing(const Options& options);
/// --quality auto, where the mode wants it (`wanted`: headless with --quality auto; the window and --xr
/// unless --quality scene): `setup`'s spacing from ChooseQuality for `config`, unless --spacing is given
/// or a state file (`start`, may be null) fixes it (logged). Errors name the scene file.
Status ApplyAutoQuality(const Options& options, bool wanted, const StateFile* start, const sim::SolverConfig& config,
                        sim::SceneSetup* setup);

/// What every mode starts from: the scene with the command line's changes (LoadSceneWithOptions), its
/// setup with a --load-state file's spacing, and that file, read before anything is allocated (a bad
/// one is one line before any window opens; ReadStartState).
struct RunStart {
  SceneFile scene;
  sim::SceneSetup setup;
  std::shared_ptr<const StateFile> state;  // null without --load-state
};
Status PrepareStart(const Options& options, RunStart* out);
/// The solver's device and threads for the window and --xr: without --threads, one core is left to the
/// frame loop (logged when `log`).
sim::SolverConfig InteractiveSolverConfig(const Options& options, bool log);

}  // namespace sphxr::app
