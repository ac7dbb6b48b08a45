#pragma once
// Cubic spline smoothing kernel (Monaghan 1992), written with the support radius H (W = 0 for r >= H):
//   q = r/H, sigma = 8/(pi H^3)
//   W(q) = sigma * (6(q^3 - q^2) + 1)   for 0 <= q <= 1/2
//        = sigma * 2(1 - q)^3           for 1/2 < q < 1
// Normalisation, gradient antisymmetry, zero gradient sum and compact support are tested in
// tests/sim/kernel_test.cpp.
#include "sphxr/common/hd.h"
#include "sphxr/sim/vec.h"

namespace sphxr::sim {

struct CubicSpline {
  float H = 1.0f;       // support radius
  float H2 = 1.0f;
  float invH = 1.0f;
  float sigma = 0.0f;   // 8 / (pi H^3)
  float gradA = 0.0f;   // 6 sigma / H^2, for q <= 1/2
  float gradB = 0.0f;   // 6 sigma / H,   for q > 1/2

  static CubicSpline Make(float supportRadius) {
    CubicSpline k;
    k.H = supportRadius;
    k.H2 = supportRadius * supportRadius;
    k.invH = 1.0f / supportRadius;
    k.sigma = 8.0f / (3.14159265358979f * supportRadius * supportRadius * supportRadius);
    k.gradA = 6.0f * k.sigma / k.H2;
    k.gradB = 6.0f * k.sigma / supportRadius;
    return k;
  }

  SPHXR_HD SPHXR_INLINE float W(float r) const {
    const float q = r * invH;
    if (q >= 1.0f) return 0.0f;
    if (q <= 0.5f) return sigma * (6.0f * (q * q * q - q * q) + 1.0f);
    const float t = 1.0f - q;
    return sigma * 2.0f * t * t * t;
  }

  /// g with grad W(x) = g * x for |x| = r (so the gradient is finite and zero at r = 0).
  SPHXR_HD SPHXR_INLINE float GradFactor(float r) const {
    const float q = r * invH;
    if (q >= 1.0f) return 0.0f;
    if (q <= 0.5f) return gradA * (3.0f * q - 2.0f);
    const float t = 1.0f - q;
    return -gradB * t * t / r;
  }

  SPHXR_HD SPHXR_INLINE Vec3 Grad(Vec3 x) const { return x * GradFactor(Length(x)); }
};

}  // namespace sphxr::sim
