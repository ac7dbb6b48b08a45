#pragma once
// Kinematic rigid bodies that move through the fluid as boundary particles (paddles; interaction/
// drives them). The solver knows a body by its shape primitives (for the push-out that keeps fluid out
// of it) and its boundary particles in the body frame (sampled by interaction/, volumes weighted by the
// solver after Akinci et al. 2012). Everything here is plain data and host+device math.
#include <vector>

#include "sphxr/sim/hd.h"
#include "sphxr/sim/vec.h"

namespace sphxr::sim {

/// Unit quaternion, w + xi + yj + zk; rotates body-frame vectors into the world frame.
struct Quat {
  float w = 1, x = 0, y = 0, z = 0;
};

SPHXR_HD SPHXR_INLINE bool Finite(Quat q) { return IsFinite(q.w) && IsFinite(q.x) && IsFinite(q.y) && IsFinite(q.z); }
SPHXR_HD SPHXR_INLINE Quat Mul(Quat a, Quat b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
SPHXR_HD SPHXR_INLINE Quat Conjugate(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }
SPHXR_HD SPHXR_INLINE Quat Normalized(Quat q) {
  const float n = sqrtf(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > 0.0f)) return Quat{};
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
/// R(q) v.
SPHXR_HD SPHXR_INLINE Vec3 Rotate(Quat q, Vec3 v) {
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = Cross(u, v) * 2.0f;
  return v + t * q.w + Cross(u, t);
}
/// Spherical linear interpolation along the shorter arc; nlerp when the arc is tiny.
SPHXR_HD SPHXR_INLINE Quat Slerp(Quat a, Quat b, float u) {
  float d = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
  if (d < 0.0f) {
    b = {-b.w, -b.x, -b.y, -b.z};
    d = -d;
  }
  float wa = 1.0f - u, wb = u;
  if (d < 0.9995f) {
    const float theta = acosf(d);
    const float s = sinf(theta);
    wa = sinf(wa * theta) / s;
    wb = sinf(wb * theta) / s;
  }
  return Normalized(Quat{wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z});
}
/// The rotation vector (axis * angle, radians, angle in [0, pi]) of the unit quaternion q.
SPHXR_HD SPHXR_INLINE Vec3 RotationVector(Quat q) {
  if (q.w < 0.0f) q = {-q.w, -q.x, -q.y, -q.z};
  const float s = sqrtf(q.x * q.x + q.y * q.y + q.z * q.z);
  if (s < 1e-7f) return Vec3{2.0f * q.x, 2.0f * q.y, 2.0f * q.z};
  const float angle = 2.0f * atan2f(s, q.w);
  return Vec3{q.x, q.y, q.z} * (angle / s);
}

struct RigidPose {
  Vec3 position;     // m, world position of the body origin
  Quat orientation;  // body frame -> world frame
};

/// A solid primitive in the body frame. Box: centre `a`, half extents `b` (axis-aligned in the body
/// frame). Capsule: the segment from `a` to `b`, radius `radius`.
struct ShapePrimitive {
  enum class Kind : int { kBox, kCapsule };
  Kind kind = Kind::kBox;
  Vec3 a, b;
  float radius = 0.0f;
};

/// Signed distance of a body-frame point to a primitive (negative inside) and the outward unit normal
/// of the nearest surface point.
SPHXR_HD SPHXR_INLINE float ShapeDistance(const ShapePrimitive& s, Vec3 p, Vec3* normal) {
  if (s.kind == ShapePrimitive::Kind::kBox) {
    const Vec3 d = p - s.a;
    const float q[3] = {fabsf(d.x) - s.b.x, fabsf(d.y) - s.b.y, fabsf(d.z) - s.b.z};
    const float sign[3] = {d.x < 0.0f ? -1.0f : 1.0f, d.y < 0.0f ? -1.0f : 1.0f, d.z < 0.0f ? -1.0f : 1.0f};
    if (q[0] <= 0.0f && q[1] <= 0.0f && q[2] <= 0.0f) {  // inside: the nearest face
      int axis = 0;
      if (q[1] > q[axis]) axis = 1;
      if (q[2] > q[axis]) axis = 2;
      *normal = Vec3{axis == 0 ? sign[0] : 0.0f, axis == 1 ? sign[1] : 0.0f, axis == 2 ? sign[2] : 0.0f};
      return q[axis];
    }
    const Vec3 out{fmaxf(q[0], 0.0f) * sign[0], fmaxf(q[1], 0.0f) * sign[1], fmaxf(q[2], 0.0f) * sign[2]};
    const float len = Length(out);
    *normal = out * (1.0f / len);
    return len;
  }
  const Vec3 ab = s.b - s.a;
  const float len2 = Dot(ab, ab);
  float t = len2 > 0.0f ? Dot(p - s.a, ab) / len2 : 0.0f;
  t = fminf(fmaxf(t, 0.0f), 1.0f);
  const Vec3 r = p - (s.a + ab * t);
  const float len = Length(r);
  if (len > 1e-12f) {
    *normal = r * (1.0f / len);
  } else {  // on the axis: any direction perpendicular to it
    const Vec3 axis = len2 > 0.0f ? ab * (1.0f / sqrtf(len2)) : Vec3{0.0f, 1.0f, 0.0f};
    const Vec3 c = fabsf(axis.x) < 0.9f ? Vec3{1.0f, 0.0f, 0.0f} : Vec3{0.0f, 1.0f, 0.0f};
    const Vec3 n = Cross(axis, c);
    *normal = n * (1.0f / Length(n));
  }
  return len - s.radius;
}

/// Signed distance to the union of `count` primitives, with the normal of the nearest one.
SPHXR_HD SPHXR_INLINE float UnionDistance(const ShapePrimitive* shapes, int count, Vec3 p, Vec3* normal) {
  float best = 3.4e38f;
  for (int k = 0; k < count; ++k) {
    Vec3 n;
    const float d = ShapeDistance(shapes[k], p, &n);
    if (d < best) {
      best = d;
      *normal = n;
    }
  }
  return best;
}

/// A kinematic rigid body of the scene: its solid (union of primitives) and its boundary particles,
/// both in the body frame. The solver moves it along the targets given by Solver::SetBodyTarget.
struct RigidBodySetup {
  std::vector<ShapePrimitive> shapes;
  std::vector<Vec3> points;   // boundary particles (body frame), e.g. interaction::SamplePaddle
  float viscosity = -1.0f;    // artificial viscosity alpha fluid-body; < 0: solver.boundary_viscosity
  RigidPose pose;             // pose at time 0
};

/// Force and torque of the fluid on a body during the last step (sum of the boundary particles'
/// reactions; torque about the body origin at the start of that step).
struct BodyLoad {
  Vec3 force;   // N
  Vec3 torque;  // N m
};

}  // namespace sphxr::sim
