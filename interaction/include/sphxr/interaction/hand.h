#pragma once
// The neutral hand input: what the XR layer (a controller's grip pose), the desktop mouse and scripted
// trajectories (trajectory.h) all fill, and what a paddle follows (paddle.h). No OpenXR or GL types.
#include "sphxr/common/math.h"
#include "sphxr/sim/vec.h"

namespace sphxr::interaction {

// Poses are the math module's (sphxr/common/math.h): position in the world (the simulation's frame),
// orientation hand frame -> world frame.
using sphxr::Pose;
using sphxr::Quat;

struct HandInput {
  bool tracked = false;       // false: the pose is stale (the paddle holds, then withdraws)
  Pose pose;
  bool hasVelocity = false;   // the source measured the velocities below (XR runtimes often do)
  sim::Vec3 linearVelocity, angularVelocity;  // m/s, rad/s (world)
  float trigger = 0, grip = 0;  // 0..1
  double time = 0;            // s, the time the pose is for (the predicted display time in XR)
};

}  // namespace sphxr::interaction
