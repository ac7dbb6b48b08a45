#pragma once
// `sphxr --xr`: the water in a headset. A GLFW window (the desktop mirror: the left eye and a small
// panel) owns the GL context that the xr::Session draws with; the simulation runs on the SimWorker
// thread, so the headset's frame loop never waits on a step. Each frame: the controllers' grip poses
// become interaction::HandInput for the paddles, each eye draws the newest snapshot with
// render::Renderer, the paddles' haptic amplitudes go back to the controllers.
//
// The tank is placed in the play space (STAGE: floor at y = 0, user facing -z) by a translation only:
// its centre at `XrPlacement` below. The sim frame is the scene's own; play = sim + offset.
#include <cstdint>
#include <string>

#include "sphxr/app/options.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/params.h"

namespace sphxr::app {

/// Where the tank stands in the play space: its centre, in metres (a table in front of the user,
/// where the simulated headset looks by default).
struct XrPlacement {
  float centerX = 0.0f, centerY = 1.0f, centerZ = -0.4f;
};
/// The translation from the scene's frame to the play space for `tank` (play = sim + offset).
sim::Vec3 XrSceneOffset(const sim::Aabb& tank, const XrPlacement& placement = {});

/// How an XR run ended.
struct XrOutcome {
  bool started = false;    // a session was created
  bool fallback = false;   // the error is the headset's (no display, no runtime, no session): fall back
  bool lost = false;       // the session or instance was lost mid-run (fall back, or exit)
  int interrupted = 0;     // SIGINT, SIGTERM or SIGHUP ended the session (its water saved as a lost one's)
  std::string savedState;  // lost: where the running water was saved (the window continues from it)
  int64_t frames = 0;      // frames whose update ran
  int64_t rendered = 0;    // frames with eyes drawn
  std::string message;     // how the session ended, one line
  std::string states;      // the session states seen, in order ("IDLE READY ...")
  double frameMsP50 = 0, frameMsP90 = 0;  // wall time between frames
  double busyMsP50 = 0, busyMsP90 = 0;    // a frame's time outside xrWaitFrame (sync, update, eyes, end)
  int64_t lateFrames = 0;                 // frames more than 1.5 display periods after the previous one
  double meanFluidSpeed = 0;              // m/s, over the particles of the last snapshot
  double peakMeanFluidSpeed = 0;          // m/s, the largest mean over the snapshots drawn
};

/// Runs the headset until the session ends (the runtime, the window closing, `--frame-limit` frames, a
/// SIGINT, SIGTERM or SIGHUP: the session is ended as the end button ends it, then saved as a lost one).
/// An error status means no session could be started (no display, no runtime, a runtime failing at
/// session creation, a bad scene): one line, nothing was shown; the caller falls back.
Status RunXr(const Options& options, XrOutcome* outcome);

/// True when an OpenXR runtime answers (without creating a session); otherwise `why` says why.
bool XrRuntimeAvailable(std::string* why);

}  // namespace sphxr::app
