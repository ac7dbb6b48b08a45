#pragma once
// The walls' contact force (tank.wall_contact, on by default; docs/design/walls.md): a short-range
// repulsion from the tank's faces and the static obstacles, in the line of Monaghan's repulsive
// boundary forces (Monaghan 1994; Monaghan & Kajtar 2009), acting only where the boundary particles
// cannot: on water with no pressure (a film or a spray particle, p = 0) that drifts at the wall.
//
// Where it acts: a fluid particle rests half a spacing from a face (0.5 dx); the clamp box lies a
// quarter spacing from it (0.25 dx, stages/clamp.h). The contact zone is the last `contactWidth`
// (0.15 dx) before the clamp box, from 0.4 dx of the face inwards, so water at rest, even compressed
// by 20 %, never feels it. Inside the zone the acceleration points away from the wall and grows as
// K s^2, s = (depth into the zone) / width: a potential, so the contact stores and returns energy
// (no drift in the energy test) and takes none from a particle that leaves.
//
// K is set to stop a particle arriving at a quarter of the sound speed within the zone (its potential
// at the clamp box, K width / 3, equals (c/4)^2 / 2), and capped so that symplectic Euler resolves the
// spring at the zone's floor: omega dt <= 1.5 with omega^2 = 2 K / width. WCSPH's acoustic step never
// reaches the cap; DFSPH's longer step does, and its pressure solve is what holds its walls.
#include "stages/views.h"

namespace sphxr::sim {

/// The one-sided contact acceleration of depth `e` into a zone of width `w` (e <= 0: outside it).
SPHXR_HD SPHXR_INLINE float ContactAcceleration(float strength, float w, float e) {
  if (e <= 0.0f) return 0.0f;
  const float s = fminf(e / w, 1.0f);
  return strength * s * s;
}

/// The contact acceleration on a fluid particle at x from the tank's faces (the top one when the tank
/// is closed) and the obstacles; zero for a particle farther than the zone from every wall.
SPHXR_HD SPHXR_INLINE Vec3 WallContact(const Physics& ph, Vec3 x, float dt) {
  Vec3 a{0.0f, 0.0f, 0.0f};
  const float w = ph.contactWidth;
  // The cap from the step: omega dt <= 1.5, omega^2 = 2 K / w.
  const float strength = fminf(ph.contactStrength, 1.125f * w / (dt * dt));
  // Tank faces: the zone ends at the clamp box (domainMin/Max).
  a.x += ContactAcceleration(strength, w, ph.domainMin.x + w - x.x);
  a.x -= ContactAcceleration(strength, w, x.x - (ph.domainMax.x - w));
  a.y += ContactAcceleration(strength, w, ph.domainMin.y + w - x.y);
  if (ph.closedTop) a.y -= ContactAcceleration(strength, w, x.y - (ph.domainMax.y - w));
  a.z += ContactAcceleration(strength, w, ph.domainMin.z + w - x.z);
  a.z -= ContactAcceleration(strength, w, x.z - (ph.domainMax.z - w));
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
    const float push = ContactAcceleration(strength, w, w - r) / r;
    a.x += push * d.x;
    a.y += push * d.y;
    a.z += push * d.z;
  }
  return a;
}

}  // namespace sphxr::sim
