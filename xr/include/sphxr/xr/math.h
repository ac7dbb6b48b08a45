#pragma once
// What poses become at the OpenXR boundary (nothing outside xr/ sees OpenXR types): the math module's
// Vec3, Quat and Pose (sphxr/common/math.h; session.cpp converts OpenXR's (x, y, z, w) quaternions),
// and the view and projection matrices. Conventions are OpenXR's: right-handed, +y up, -z forward,
// metres; matrices are column-major (m[col * 4 + row]) for OpenGL.
#include <array>
#include <cmath>

#include "sphxr/common/math.h"

namespace sphxr::xr {

using sphxr::Pose;
using sphxr::Quat;
using sphxr::Vec3;

struct Mat4 {
  std::array<float, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float operator()(int row, int col) const { return m[col * 4 + row]; }
};
/// Field of view of one eye as OpenXR gives it: signed angles from the view axis (left, down < 0).
struct Fov {
  float angleLeft = -0.8f, angleRight = 0.8f, angleUp = 0.8f, angleDown = -0.8f;
};

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
