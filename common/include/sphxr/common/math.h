#pragma once
// The one math module: small vector, rotation and box types shared by host and device code (sim's
// stages, the paddles, the app). Vec4 is the 16-byte storage type of per-particle vectors (xyz + one
// spare lane), matching CUDA's float4 alignment. Quaternions are unit, w + xi + yj + zk, and rotate a
// body (or hand) frame into the world frame.
#include <cmath>

#include "sphxr/common/hd.h"

namespace sphxr {

struct Vec3 {
  float x = 0, y = 0, z = 0;
};

struct alignas(16) Vec4 {
  float x = 0, y = 0, z = 0, w = 0;
};

SPHXR_HD SPHXR_INLINE Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
SPHXR_HD SPHXR_INLINE Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
SPHXR_HD SPHXR_INLINE Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
SPHXR_HD SPHXR_INLINE Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
SPHXR_HD SPHXR_INLINE Vec3 operator*(float s, Vec3 a) { return {a.x * s, a.y * s, a.z * s}; }
SPHXR_HD SPHXR_INLINE Vec3& operator+=(Vec3& a, Vec3 b) {
  a.x += b.x;
  a.y += b.y;
  a.z += b.z;
  return a;
}
SPHXR_HD SPHXR_INLINE Vec3& operator-=(Vec3& a, Vec3 b) {
  a.x -= b.x;
  a.y -= b.y;
  a.z -= b.z;
  return a;
}
SPHXR_HD SPHXR_INLINE float Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SPHXR_HD SPHXR_INLINE Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
SPHXR_HD SPHXR_INLINE float Length(Vec3 a) { return sqrtf(Dot(a, a)); }
SPHXR_HD SPHXR_INLINE Vec3 Xyz(Vec4 a) { return {a.x, a.y, a.z}; }

/// x is neither NaN nor infinite (x - x is NaN for both). Written out so that it is the same function on
/// the host and the device (no fast-math flags are used, so the compiler may not fold it to true).
SPHXR_HD SPHXR_INLINE bool IsFinite(float x) { return x - x == 0.0f; }
SPHXR_HD SPHXR_INLINE bool Finite(Vec3 v) { return IsFinite(v.x) && IsFinite(v.y) && IsFinite(v.z); }
SPHXR_HD SPHXR_INLINE Vec4 MakeVec4(Vec3 a, float w = 0.0f) { return {a.x, a.y, a.z, w}; }

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

/// Rotation of `radians` about the unit `axis` (right-hand rule).
SPHXR_HD SPHXR_INLINE Quat AxisAngle(Vec3 axis, float radians) {
  const float s = sinf(radians * 0.5f);
  return {cosf(radians * 0.5f), axis.x * s, axis.y * s, axis.z * s};
}

/// A rigid transform: rotate by `orientation`, then translate by `position`.
struct Pose {
  Vec3 position;     // m
  Quat orientation;  // body frame -> world frame
};

/// a * b: the transform that applies b first, then a (a pose of b's frame given in a's frame).
SPHXR_HD SPHXR_INLINE Pose operator*(const Pose& a, const Pose& b) {
  return {a.position + Rotate(a.orientation, b.position), Normalized(Mul(a.orientation, b.orientation))};
}
SPHXR_HD SPHXR_INLINE Pose Inverse(const Pose& p) {
  const Quat qi = Conjugate(p.orientation);
  return {Rotate(qi, p.position * -1.0f), qi};
}
SPHXR_HD SPHXR_INLINE Vec3 Transform(const Pose& p, Vec3 v) { return p.position + Rotate(p.orientation, v); }

/// An axis-aligned box.
struct Aabb {
  Vec3 min, max;
};

}  // namespace sphxr
