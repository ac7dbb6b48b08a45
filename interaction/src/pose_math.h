#pragma once
// Pose arithmetic of the paddles (the math module's types, sphxr/common/math.h).
#include "sphxr/interaction/hand.h"
#include "sphxr/sim/rigid.h"

namespace sphxr::interaction {

/// Position linear, rotation slerp.
inline Pose Interpolate(const Pose& a, const Pose& b, float u) {
  return Pose{a.position + (b.position - a.position) * u, Slerp(a.orientation, b.orientation, u)};
}

/// Rotation angle (rad) from a to b.
inline float AngleBetween(Quat a, Quat b) {
  return Length(RotationVector(Mul(b, Conjugate(a))));
}

}  // namespace sphxr::interaction
