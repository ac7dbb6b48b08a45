#pragma once
// The headless runner: `sphxr --headless --scene FILE ...`. The runner is a library function so that
// tests and benchmarks drive exactly what a user runs; its outputs are sinks of the Simulation
// (app/src/*_sink.h).
#include <cstdint>
#include <string>

#include "sphxr/app/options.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

/// What a headless run measured (also printed as the summary).
struct RunSummary {
  int fluid = 0;
  int boundary = 0;
  int64_t steps = 0;
  double simulatedTime = 0.0;
  double wallSeconds = 0.0;
  double msPerStep = 0.0;
  double stageMsPerStep[static_cast<int>(sim::Stage::kCount)] = {};
  sim::LaunchCounts countsAtStart;   // the solver's launch counts before the first step
  sim::LaunchCounts counts;          // what the run's steps asked of the device (sphxr/sim/launch_counts.h)
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
  int diffuse[3] = {-1, -1, -1};     // solver.diffuse: spray, foam and bubbles at the end (-1: off)
};

/// Runs a scene headless: load, apply overrides, simulate, export, summarise. The summary is printed
/// to stdout; errors come back as the status. A SIGINT (Ctrl-C) or SIGTERM during the steps stops the
/// run after the step in progress: the stats CSV keeps whole rows, the particles and the surface are
/// exported once more at that step (when exports are on), the summary covers the run so far, and
/// `summary->interrupted` names the signal (status ok). A second signal ends the process at once.
Status RunHeadless(const Options& options, RunSummary* summary);

}  // namespace sphxr::app
