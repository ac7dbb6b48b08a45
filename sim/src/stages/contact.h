#pragma once
// The walls' contact force (tank.wall_contact, on by default; docs/design/walls.md): a short-range
// repulsion from the tank's faces and the static obstacles, in the line of Monaghan's repulsive
// boundary forces (Monaghan 1994; Monaghan & Kajtar 2009), acting only where the boundary particles
// cannot: on water with no pressure (a film or a spray particle, p = 0) that drifts at the wall.
//
// Where it acts: a fluid particle rests half a spacing from a face (0.5 dx); the clamp box lies a
// quarter spacing from it (0.25 dx, stages/clamp.h). The contact zone is the last `contactWidth`
// (0.1 dx) before the clamp box, from 0.35 dx of the face inwards, so water at rest, even compressed
// by 15 % (its first layer 0.85 dx from the wall's sheet instead of 1 dx), never feels it; narrow, so that it changes as little as it can of the flow along a wall (a
// pressure-free film on a floor rests at its edge, 0.35 dx from the face, not at the clamp box's
// 0.25 dx; the floor's friction on it depends on that distance). Inside the zone the acceleration points away from the wall and grows as
// K s^2, s = (depth into the zone) / width, and the velocity along the wall's normal is damped
// critically there: water that meets a wall loses its normal speed, as at the clamp it replaces (an
// inelastic wall), instead of bouncing back off a spring. An elastic contact (the spring alone) ran the
// Martin & Moyce front 0.5 % further ahead and raised the column height by 1.3 % of the measurement:
// the film it throws back off the side walls keeps its energy.
//
// K is set to stop a particle arriving at a quarter of the sound speed within the zone (its potential
// at the clamp box, K width / 3, equals (c/4)^2 / 2), and capped so that symplectic Euler resolves the
// spring at the zone's floor: omega dt <= 1.5 with omega^2 = 2 K / width. At WCSPH's acoustic step the
// cap lowers K by up to about 2x; the capped contact still stops a particle arriving at 0.17 c (cfl 0.4,
// support 2.5 dx) to 0.22 c (support 2 dx). Under DFSPH only on particles lighter than rho0
// (Physics::contactBelowRestOnly, DriftAndStore), the ones its density solve cannot push: DFSPH's
// first layer of water at rest sits inside the zone, and must not carry the contact (solver.cpp).
#include "stages/views.h"

namespace sphxr::sim {

/// The one-sided contact acceleration of depth `e` into a zone of width `w` (e <= 0: outside it).
SPHXR_HD SPHXR_INLINE float ContactAcceleration(float strength, float w, float e) {
  if (e <= 0.0f) return 0.0f;
  const float s = fminf(e / w, 1.0f);
  return strength * s * s;
}

/// The contact on a fluid particle at x with velocity v over a step dt, from the tank's faces (the top
/// one when the tank is closed) and the obstacles: in a zone, the spring's kick along the wall's normal,
/// and the normal velocity damped critically (gamma = 2 omega, implicit: v_n / (1 + gamma dt), stable
/// at any step), so that water meeting a wall loses its normal speed as at an inelastic wall instead of
/// bouncing back. Nothing changes for a particle farther than the zone from every wall.
SPHXR_HD SPHXR_INLINE void WallContact(const Physics& ph, Vec3 x, float dt, Vec4* v) {
  const float w = ph.contactWidth;
  // The cap from the step: omega dt <= 1.5, omega^2 = 2 K / w.
  const float strength = fminf(ph.contactStrength, 1.125f * w / (dt * dt));
  const float damping = 1.0f / (1.0f + 2.0f * sqrtf(2.0f * strength / w) * dt);
  // One face: depth e into its zone, n its inward normal's sign along the axis.
  auto face = [&](float e, float sign, float* vAxis) {
    if (e <= 0.0f) return;
    *vAxis = (*vAxis + sign * dt * ContactAcceleration(strength, w, e)) * damping;
  };
  // Tank faces: the zone ends at the clamp box (domainMin/Max).
  face(ph.domainMin.x + w - x.x, 1.0f, &v->x);
  face(x.x - (ph.domainMax.x - w), -1.0f, &v->x);
  face(ph.domainMin.y + w - x.y, 1.0f, &v->y);
  if (ph.closedTop) face(x.y - (ph.domainMax.y - w), -1.0f, &v->y);
  face(ph.domainMin.z + w - x.z, 1.0f, &v->z);
  face(x.z - (ph.domainMax.z - w), -1.0f, &v->z);
  // Obstacles: the zone lies outside each one's grown box (the clamp's), along the direction from its
  // nearest point, so edges and corners push diagonally. A particle inside is the clamp's.
  for (int k = 0; k < ph.obstacleCount; ++k) {
    const Vec3 lo = ph.obstacleMin[k], hi = ph.obstacleMax[k];
    const Vec3 d{x.x < lo.x ? x.x - lo.x : (x.x > hi.x ? x.x - hi.x : 0.0f),
                 x.y < lo.y ? x.y - lo.y : (x.y > hi.y ? x.y - hi.y : 0.0f),
                 x.z < lo.z ? x.z - lo.z : (x.z > hi.z ? x.z - hi.z : 0.0f)};
    const float r2 = d.x * d.x + d.y * d.y + d.z * d.z;
    if (r2 <= 0.0f || r2 >= w * w) continue;
    const float r = sqrtf(r2);
    const Vec3 n{d.x / r, d.y / r, d.z / r};
    const float vn = v->x * n.x + v->y * n.y + v->z * n.z;
    const float change = (vn + dt * ContactAcceleration(strength, w, w - r)) * damping - vn;
    v->x += change * n.x;
    v->y += change * n.y;
    v->z += change * n.z;
  }
}

}  // namespace sphxr::sim
