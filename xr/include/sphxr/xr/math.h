#pragma once
// xr's own plain math types: what poses become at the OpenXR boundary (nothing outside xr/ sees
// OpenXR types). Conventions are OpenXR's: right-handed, +y up, -z forward, metres; quaternions
// are unit (x, y, z, w); matrices are column-major (m[col * 4 + row]) for OpenGL.
#include <array>
#include <cmath>

namespace sphxr::xr {

struct Vec3 {
  float x = 0, y = 0, z = 0;
};
struct Quat {
  float x = 0, y = 0, z = 0, w = 1;
};
/// A rigid transform: rotate by `orientation`, then translate by `position`.
struct Pose {
  Quat orientation;
  Vec3 position;
};
struct Mat4 {
  std::array<float, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float operator()(int row, int col) const { return m[col * 4 + row]; }
};
/// Field of view of one eye as OpenXR gives it: signed angles from the view axis (left, down < 0).
struct Fov {
  float angleLeft = -0.8f, angleRight = 0.8f, angleUp = 0.8f, angleDown = -0.8f;
};

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline float Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float Length(Vec3 a) { return std::sqrt(Dot(a, a)); }

inline Quat operator*(Quat a, Quat b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
inline Quat Conjugate(Quat q) { return {-q.x, -q.y, -q.z, q.w}; }
inline Quat Normalize(Quat q) {
  float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return n > 0 ? Quat{q.x / n, q.y / n, q.z / n, q.w / n} : Quat{};
}
/// Rotation of `radians` about the unit `axis` (right-hand rule).
inline Quat AxisAngle(Vec3 axis, float radians) {
  float s = std::sin(radians * 0.5f);
  return {axis.x * s, axis.y * s, axis.z * s, std::cos(radians * 0.5f)};
}
inline Vec3 Rotate(Quat q, Vec3 v) {
  // v' = v + 2w (u x v) + 2 u x (u x v), u = q.xyz
  Vec3 u{q.x, q.y, q.z};
  Vec3 t = Cross(u, v) * 2.0f;
  return v + t * q.w + Cross(u, t);
}
/// Shortest-arc spherical interpolation, t in [0, 1].
inline Quat Slerp(Quat a, Quat b, float t) {
  float d = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
  if (d < 0) {
    b = {-b.x, -b.y, -b.z, -b.w};
    d = -d;
  }
  if (d > 0.9995f) {
    return Normalize({a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t, a.w + (b.w - a.w) * t});
  }
  float theta = std::acos(d), s = std::sin(theta);
  float wa = std::sin((1 - t) * theta) / s, wb = std::sin(t * theta) / s;
  return {wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z, wa * a.w + wb * b.w};
}

/// a * b: the transform that applies b first, then a (a pose of b's frame given in a's frame).
inline Pose operator*(const Pose& a, const Pose& b) {
  return {Normalize(a.orientation * b.orientation), a.position + Rotate(a.orientation, b.position)};
}
inline Pose Inverse(const Pose& p) {
  Quat qi = Conjugate(p.orientation);
  return {qi, Rotate(qi, p.position * -1.0f)};
}
inline Vec3 Transform(const Pose& p, Vec3 v) { return p.position + Rotate(p.orientation, v); }

inline Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a(row, k) * b(k, c);
      r.m[c * 4 + row] = s;
    }
  return r;
}
/// The model matrix of a pose (object -> parent).
inline Mat4 MatrixFromPose(const Pose& p) {
  Mat4 r;
  Vec3 cx = Rotate(p.orientation, {1, 0, 0}), cy = Rotate(p.orientation, {0, 1, 0}),
       cz = Rotate(p.orientation, {0, 0, 1});
  r.m = {cx.x, cx.y, cx.z, 0, cy.x, cy.y, cy.z, 0, cz.x, cz.y, cz.z, 0, p.position.x, p.position.y, p.position.z, 1};
  return r;
}
/// The view matrix of an eye whose pose (eye -> space) is `eye`.
inline Mat4 ViewMatrix(const Pose& eye) { return MatrixFromPose(Inverse(eye)); }
/// OpenGL projection (clip z in [-w, w]) for an asymmetric OpenXR field of view.
inline Mat4 ProjectionMatrix(const Fov& fov, float nearZ, float farZ) {
  float l = std::tan(fov.angleLeft), r = std::tan(fov.angleRight);
  float u = std::tan(fov.angleUp), d = std::tan(fov.angleDown);
  float w = r - l, h = u - d;
  Mat4 p;
  p.m = {2 / w, 0, 0, 0,  //
         0, 2 / h, 0, 0,  //
         (r + l) / w, (u + d) / h, -(farZ + nearZ) / (farZ - nearZ), -1,
         0, 0, -2 * farZ * nearZ / (farZ - nearZ), 0};
  return p;
}

}  // namespace sphxr::xr
