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
  sim::Device device = sim::Device::kAuto;
  int threads = 0;          // 0 = all cores
  float spacing = 0.0f;     // m; 0 = the scene's spacing
  int64_t exportEvery = 0;  // steps between particle exports (0 = none)
  std::string outDir = "out";
  std::string exportFormat = "ply";  // ply | vtk
  std::string statsPath;    // per-step CSV
  bool validate = false;
  int reuse = -1;           // -1 = as the scene says, 0 = off, 1 = on (the scene's or default parameters)
  std::vector<std::string> sets;  // solver parameter overrides "key=value"
  int progress = -1;        // -1 = when stderr is a terminal
  bool help = false;
};

/// Parses argv. Values are checked here (a bad number is a one-line error naming the flag).
Status ParseCommandLine(int argc, const char* const* argv, Options* out);
std::string UsageText();

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
  int64_t lost = 0;                  // particles missing at the end (always 0: clamped, never removed)
  int64_t exports = 0;
  float surgeFront = -1.0f;          // dam-break probe: Z = front / a at the end (-1 when not probed)
  float columnHeight = -1.0f;        // dam-break probe: H = h / 2a at the end
};

/// Runs a scene headless: load, apply overrides, simulate, export, summarise. The summary is printed
/// to stdout; errors come back as the status.
Status RunHeadless(const Options& options, RunSummary* summary);

}  // namespace sphxr::app
