#pragma once
// The clamp behind the walls: a fluid particle that comes within a quarter spacing of a tank face, or
// into an obstacle, is put back there with its velocity into the wall removed, and counted where it
// was caught (params.h kClampSites; Totals::clampedAt). The boundary particles are what should hold the
// water; the clamp is the safety net, and the summary reports how often it caught something.
//
// Where the clamp sits: the tank's boundary particles lie half a spacing behind each face, the fluid
// lattice half a spacing in front of it, and the clamp box a quarter spacing in front of it. A clamped
// particle has come halfway from its rest position to the face, to 3/4 of a spacing from the first
// sheet of wall particles.
#include "stages/views.h"

namespace sphxr::sim {

/// Puts a particle outside the box [lo, hi] back on its nearest point, with the velocity out of the box
/// removed; true when it did.
SPHXR_HD SPHXR_INLINE bool ClampIntoBox(Vec3 lo, Vec3 hi, Vec4* x, Vec4* v) {
  bool clamped = false;
  if (x->x < lo.x) { x->x = lo.x; if (v->x < 0.0f) v->x = 0.0f; clamped = true; }
  if (x->x > hi.x) { x->x = hi.x; if (v->x > 0.0f) v->x = 0.0f; clamped = true; }
  if (x->y < lo.y) { x->y = lo.y; if (v->y < 0.0f) v->y = 0.0f; clamped = true; }
  if (x->y > hi.y) { x->y = hi.y; if (v->y > 0.0f) v->y = 0.0f; clamped = true; }
  if (x->z < lo.z) { x->z = lo.z; if (v->z < 0.0f) v->z = 0.0f; clamped = true; }
  if (x->z > hi.z) { x->z = hi.z; if (v->z > 0.0f) v->z = 0.0f; clamped = true; }
  return clamped;
}

/// Puts a particle that left the domain back on its edge with the outward velocity removed; true when
/// it did (the step counts them: acceleration.w, StepReductionOp).
SPHXR_HD SPHXR_INLINE bool ClampToDomain(const Physics& ph, Vec4* x, Vec4* v) {
  return ClampIntoBox(ph.domainMin, ph.domainMax, x, v);
}

/// Puts a particle strictly inside the box [lo, hi] on the box's nearest face, with the velocity into
/// the box removed; true when it did.
SPHXR_HD SPHXR_INLINE bool PushOutOfBox(Vec3 lo, Vec3 hi, Vec4* x, Vec4* v) {
  if (!(x->x > lo.x && x->x < hi.x && x->y > lo.y && x->y < hi.y && x->z > lo.z && x->z < hi.z)) return false;
  // The face the particle is nearest: axis a, side (lo or hi).
  const float depth[6] = {x->x - lo.x, hi.x - x->x, x->y - lo.y, hi.y - x->y, x->z - lo.z, hi.z - x->z};
  int face = 0;
  for (int f = 1; f < 6; ++f) {
    if (depth[f] < depth[face]) face = f;
  }
  float* xs[3] = {&x->x, &x->y, &x->z};
  float* vs[3] = {&v->x, &v->y, &v->z};
  const float bound[6] = {lo.x, hi.x, lo.y, hi.y, lo.z, hi.z};
  const int axis = face / 2;
  *xs[axis] = bound[face];
  // Low face: the outward direction is -axis, so velocity along +axis goes into the box.
  if ((face % 2 == 0) ? (*vs[axis] > 0.0f) : (*vs[axis] < 0.0f)) *vs[axis] = 0.0f;
  return true;
}

/// Puts a particle inside an obstacle (grown by the clamp inset) on the obstacle's nearest face, with the
/// velocity into the obstacle removed; true when it did. The obstacle's boundary particles should hold
/// the water; this is the safety net, as the domain clamp is for the tank.
SPHXR_HD SPHXR_INLINE bool ClampOutOfObstacles(const Physics& ph, Vec4* x, Vec4* v) {
  bool clamped = false;
  for (int k = 0; k < ph.obstacleCount; ++k) clamped = PushOutOfBox(ph.obstacleMin[k], ph.obstacleMax[k], x, v) || clamped;
  return clamped;
}

/// The clamp site (params.h kClampSites) that put particle x where it is after a clamp: the tank face
/// it sits on, else the obstacle on whose grown face it sits; -1 when none (a moving body pushed it on).
SPHXR_HD SPHXR_INLINE int ClampSiteOf(const Physics& ph, Vec3 x) {
  if (x.x == ph.domainMin.x) return 0;
  if (x.x == ph.domainMax.x) return 1;
  if (x.y == ph.domainMin.y) return 2;
  if (x.y == ph.domainMax.y) return 3;
  if (x.z == ph.domainMin.z) return 4;
  if (x.z == ph.domainMax.z) return 5;
  for (int k = 0; k < ph.obstacleCount; ++k) {
    const Vec3 lo = ph.obstacleMin[k], hi = ph.obstacleMax[k];
    const bool inside = x.x >= lo.x && x.x <= hi.x && x.y >= lo.y && x.y <= hi.y && x.z >= lo.z && x.z <= hi.z;
    const bool onFace = x.x == lo.x || x.x == hi.x || x.y == lo.y || x.y == hi.y || x.z == lo.z || x.z == hi.z;
    if (inside && onFace) return kTankFaces + k;
  }
  return -1;
}

}  // namespace sphxr::sim
