#pragma once
// Small vector types shared by host and device code. Vec4 is the 16-byte storage type of
// per-particle vectors (xyz + one spare lane), matching CUDA's float4 alignment.
#include <cmath>

#include "sphxr/sim/hd.h"

namespace sphxr::sim {

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

}  // namespace sphxr::sim
