#pragma once
// The command line and the headless runner: `sphxr --headless --scene FILE ...`. The runner is a
// library function so that tests and benchmarks drive exactly what a user runs.
#include <cstdint>
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

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
  bool help = false;
};

/// Parses argv. Values are checked here (a bad number is a one-line error naming the flag).
Status ParseCommandLine(int argc, const char* const* argv, Options* out);
std::string UsageText();

struct SceneFile;
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
struct StateFile;
/// --quality auto, where the mode wants it (`wanted`: headless with --quality auto; the window and --xr
/// unless --quality scene): `setup`'s spacing from ChooseQuality for `config`, unless --spacing is given
/// or a state file (`start`, may be null) fixes it (logged). Errors name the scene file.
Status ApplyAutoQuality(const Options& options, bool wanted, const StateFile* start, const sim::SolverConfig& config,
                        sim::SceneSetup* setup);

/// What a headless run measured (also printed as the summary).
struct RunSummary {
  int fluid = 0;
  int boundary = 0;
  int64_t steps = 0;
  double simulatedTime = 0.0;
  double wallSeconds = 0.0;
  double msPerStep = 0.0;
  double stageMsPerStep[static_cast<int>(sim::Stage::kCount)] = {};
  float meanDensityError = 0.0f;     // of the last step
  float maxDensityError = 0.0f;      // of the last step
  float peakMeanDensityError = 0.0f; // over the run
  float maxSpeed = 0.0f;             // over the run
  double meanActiveFraction = 1.0;   // reuse: mean over the steps of the fraction that computed
  int64_t clampedEvents = 0;
  double clampsPerThousand = 0.0;    // clamps per 1,000 particle-steps over the run
  std::string clampedMost;           // the wall (or obstacle) that clamped most, empty without clamps
  int64_t lost = 0;                  // particles missing at the end (always 0: clamped, never removed)
  int64_t exports = 0;
  int64_t surfaceExports = 0;
  int64_t surfaceTriangles = 0;      // of the last exported surface
  double surfaceMs = 0.0;            // mean extraction time (field + pyramid + traversal + download)
  float surgeFront = -1.0f;          // dam-break probe: Z = front / a at the end (-1 when not probed)
  float columnHeight = -1.0f;        // dam-break probe: H = h / 2a at the end
  int paddles = 0;                   // scene "paddles" section
  int paddleParticles = 0;           // their boundary particles
  int64_t pushedOut = 0;             // fluid particles pushed out of a paddle (particle-steps)
  double paddleMeanForce = 0.0;      // N, mean over steps and paddles of the filtered |force|
  float paddlePeakHaptic = 0.0f;     // largest haptic amplitude over the run
  int64_t frames = 0;                // PNG frames written to --frames DIR
  int interrupted = 0;               // the signal (SIGINT, SIGTERM) that stopped the run early, else 0
  sim::SettleReport settle;          // --settle / run.settle (time 0: not settled)
  double startTime = 0.0;            // s on the clock at the first step (a --load-state's time, else 0)
  int64_t stepsBefore = 0;           // the --load-state's step count (steps, exports and CSV rows number on from it)
  std::string stateSaved;            // --save-state: the file written
  int64_t checkpoints = 0;           // --checkpoint-every: states saved during the run
  double checkpointTime = -1.0;      // s on the clock of the last checkpoint (-1: none)
};

/// Runs a scene headless: load, apply overrides, simulate, export, summarise. The summary is printed
/// to stdout; errors come back as the status. A SIGINT (Ctrl-C) or SIGTERM during the steps stops the
/// run after the step in progress: the stats CSV keeps whole rows, the particles and the surface are
/// exported once more at that step (when exports are on), the summary covers the run so far, and
/// `summary->interrupted` names the signal (status ok). A second signal ends the process at once.
Status RunHeadless(const Options& options, RunSummary* summary);

}  // namespace sphxr::app
