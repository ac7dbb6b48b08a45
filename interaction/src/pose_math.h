#pragma once
// Conversions between the neutral hand types and the solver's rigid-body types (same layout).
#include "sphxr/interaction/hand.h"
#include "sphxr/sim/rigid.h"

namespace sphxr::interaction {

inline sim::Quat ToSim(Quat q) { return sim::Quat{q.w, q.x, q.y, q.z}; }
inline Quat ToQuat(sim::Quat q) { return Quat{q.w, q.x, q.y, q.z}; }
inline sim::RigidPose ToSim(const Pose& p) { return sim::RigidPose{p.position, ToSim(p.orientation)}; }
inline Pose ToPose(const sim::RigidPose& p) { return Pose{p.position, ToQuat(p.orientation)}; }

/// Position linear, rotation slerp.
inline Pose Interpolate(const Pose& a, const Pose& b, float u) {
  return Pose{a.position + (b.position - a.position) * u, ToQuat(sim::Slerp(ToSim(a.orientation), ToSim(b.orientation), u))};
}

/// Rotation angle (rad) from a to b.
inline float AngleBetween(Quat a, Quat b) {
  return sim::Length(sim::RotationVector(sim::Mul(ToSim(b), sim::Conjugate(ToSim(a)))));
}

}  // namespace sphxr::interaction
