#include "xr_hands.h"

#include "sphxr/app/pictures.h"

namespace sphxr::app {
namespace {

/// A paddle hangs from the hand along its body -y (paddle.h: blade below the grip); a controller's
/// grip points along its -z. Body -> grip: +90 degrees about x (body -y becomes grip -z).
constexpr Quat kGripFromPaddle{0.70710678f, 0.70710678f, 0.0f, 0.0f};

/// Where a hand's paddle may go: over the tank (5 cm beyond its sides) from its floor to 0.5 m above its
/// top. A hand elsewhere (resting at the user's side, reaching past the tank) does not drag its paddle
/// through the walls and floor: it counts as untracked, so the paddle holds, then withdraws above the
/// water (paddle.h), and re-enters when the hand comes back.
bool InReach(const sim::Vec3& p, const sim::Aabb& tank) {
  constexpr float kSide = 0.05f, kAbove = 0.5f;
  return p.x >= tank.min.x - kSide && p.x <= tank.max.x + kSide && p.z >= tank.min.z - kSide &&
         p.z <= tank.max.z + kSide && p.y >= tank.min.y && p.y <= tank.max.y + kAbove;
}

}  // namespace

interaction::HandInput ToHandInput(const xr::HandState& h, const sim::Vec3& offset, const sim::Aabb& tank,
                                   double timeSeconds) {
  interaction::HandInput in;
  in.pose.position = {h.grip.position.x - offset.x, h.grip.position.y - offset.y, h.grip.position.z - offset.z};
  in.tracked = h.poseValid && h.tracked && InReach(in.pose.position, tank);
  in.pose.orientation = Mul(h.grip.orientation, kGripFromPaddle);
  in.hasVelocity = h.velocityValid;
  in.linearVelocity = {h.linearVelocity.x, h.linearVelocity.y, h.linearVelocity.z};
  in.angularVelocity = {h.angularVelocity.x, h.angularVelocity.y, h.angularVelocity.z};
  in.trigger = h.trigger;
  in.grip = h.squeeze;
  in.time = timeSeconds;
  return in;
}

void DrawHandsAndPaddles(const xr::FrameInfo& info, const std::vector<interaction::HandInput>& hands,
                         const sim::Vec3& offset, const SimSnapshot& snap, render::FrameScene* frame) {
  frame->solids.clear();
  for (PaddlePose paddle : snap.paddles) {
    if (paddle.hand >= 0 && paddle.hand < static_cast<int>(hands.size())) {
      const xr::HandState& h = info.hands[size_t(paddle.hand)];
      const bool held = h.poseValid && h.tracked;
      if (held && !hands[size_t(paddle.hand)].tracked) paddle.pose = hands[size_t(paddle.hand)].pose;
    }
    AppendPaddleSolids(paddle, &frame->solids);
  }
  for (const xr::HandState& h : info.hands) {
    if (!(h.poseValid && h.tracked)) continue;
    interaction::Pose grip;
    grip.position = {h.grip.position.x - offset.x, h.grip.position.y - offset.y, h.grip.position.z - offset.z};
    grip.orientation = h.grip.orientation;
    AppendControllerSolids(grip, &frame->solids);
  }
}

}  // namespace sphxr::app
