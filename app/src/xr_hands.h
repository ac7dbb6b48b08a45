#pragma once
// The headset's controllers as the simulation's hands (interaction::HandInput, in the scene's frame),
// and the hands and their paddles as the frame draws them.
#include <vector>

#include "sim_worker.h"
#include "sphxr/interaction/hand.h"
#include "sphxr/render/renderer.h"
#include "sphxr/xr/session.h"

namespace sphxr::app {

/// A controller's state at `timeSeconds` as a hand of the scene (play = sim + offset): tracked only
/// while the grip is within reach of the tank.
interaction::HandInput ToHandInput(const xr::HandState& h, const sim::Vec3& offset, const sim::Aabb& tank,
                                   double timeSeconds);

/// The controllers where the hands are, and each hand's paddle in its hand: where the solver has it
/// while it is in the water, at the hand while the hand is away from the tank (its body then waits
/// above the water, out of the way, paddle.h).
void DrawHandsAndPaddles(const xr::FrameInfo& info, const std::vector<interaction::HandInput>& hands,
                         const sim::Vec3& offset, const SimSnapshot& snap, render::FrameScene* frame);

}  // namespace sphxr::app
