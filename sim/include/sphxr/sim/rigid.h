#pragma once
// Kinematic rigid bodies that move through the fluid as boundary particles (paddles; interaction/
// drives them). The solver knows a body by its shape primitives (for the push-out that keeps fluid out
// of it) and its boundary particles in the body frame (sampled by interaction/, volumes weighted by the
// solver after Akinci et al. 2012). Everything here is plain data and host+device math.
#include <vector>

#include "sphxr/common/hd.h"
#include "sphxr/sim/vec.h"

namespace sphxr::sim {

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
  Pose pose;                  // pose at time 0
};

/// Force and torque of the fluid on a body during the last step (sum of the boundary particles'
/// reactions; torque about the body origin at the start of that step).
struct BodyLoad {
  Vec3 force;   // N
  Vec3 torque;  // N m
};

}  // namespace sphxr::sim
