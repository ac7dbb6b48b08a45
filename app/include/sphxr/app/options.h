#pragma once
// What the command line asks of a run (`sphxr --help`), whatever the mode: cli.h parses it, and each
// mode (headless.h, desktop.h, xr_mode.h) takes it.
#include <cstdint>
#include <string>
#include <vector>

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

}  // namespace sphxr::app
