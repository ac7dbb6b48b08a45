#pragma once
// Diffuse particles: spray, foam and air bubbles after Ihmsen, Akinci, Akinci, Teschner, "Unified spray,
// foam and air bubbles for particle-based fluids", The Visual Computer 28 (2012) [IAAT12]. A post-step
// stage (post_step.h, diffuse_pool.h): it reads the fluid where the step left it and never writes it.
//
//   per fluid particle i, over its neighbours j within the support h (x_ij = x_i - x_j, v_ij = v_i - v_j):
//     n_i     = -sum_j V grad W_ij, normalised                         colour-field normal (outward)
//     v_diff  = sum_j |v_ij| (1 - v^_ij . x^_ij) W~(x_ij)              trapped air               [eq. 2]
//     kappa_i = sum_j (1 - n^_i . n^_j) W~(x_ij)  where x^_ji . n^_i < 0   wave-crest curvature [eq. 4]
//     delta_i = 1 where v^_i . n^_i >= 0.6, else 0                      moving along its normal  [eq. 6]
//     E_i     = 1/2 |v_i|^2                                             kinetic energy per kg    [eq. 7]
//     I = Phi(value, tau_min, tau_max) = (min(value, tau_max) - min(value, tau_min)) / (tau_max - tau_min)  [eq. 1]
//     n_d     = I_k (k_ta I_ta + k_wc I_wc) dt  diffuse particles, rounded stochastically     [eq. 8]
//   with W~(x) = 1 - |x|/h for |x| <= h [eq. 3], I_ta = Phi(v_diff), I_wc = Phi(delta kappa), I_k = Phi(E).
//   Each is sampled in the cylinder of radius r_V around x_i along v_i that the particle sweeps in
//   the step, its velocity v_i plus the same lateral offset [sec. 4.1].
//
//   per diffuse particle, from the fluid neighbours within h at its position:
//     fewer than sprayBelow: spray, v += dt g                                                   [eq. 11]
//     more than bubbleAbove: bubble, v += dt (-k_b g) + k_d (v~_f - v)                          [eq. 12]
//     else foam, carried: x += dt v~_f, its lifetime shrinks (only foam ages)                   [eq. 10]
//   v~_f = sum_f v_f W(x - x_f) / sum_f W(x - x_f), the fluid's velocity averaged at x [eq. 10]; then
//   x += dt v. A particle leaves when its lifetime is spent or it leaves the tank.
//
// Two choices of ours: the kinetic energy is per unit mass (the paper's 1/2 m v^2 with m = 1, so that
// its range does not depend on the spacing), and the wave-crest potential is evaluated only at the free
// surface (particles with at most bubbleAbove fluid neighbours, where a diffuse particle would be foam or
// spray): inside the water the colour field has no gradient and its normal is noise.
#include <cstdint>

#include "sphxr/sim/diffuse.h"
#include "stages/grid.h"
#include "stages/views.h"

namespace sphxr::sim {

// ---- random numbers: a counter-based hash, the same on every backend and thread count ---------------
/// A 32-bit integer hash (two multiply-xorshift rounds, the "lowbias32" constants of C. Wellons' hash
/// prospector): every output bit depends on every input bit.
SPHXR_HD SPHXR_INLINE uint32_t DiffuseMix(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

/// Uniform in [0, 1) from (a fluid particle's id, the step's number, a stream): no state, so the draws
/// do not depend on the order in which particles are visited, and a restored run draws the same ones.
SPHXR_HD SPHXR_INLINE float DiffuseUniform(uint32_t id, int64_t step, uint32_t stream) {
  const uint64_t s = static_cast<uint64_t>(step);
  uint32_t h = DiffuseMix(id ^ 0x9e3779b9u);
  h = DiffuseMix(h ^ static_cast<uint32_t>(s));
  h = DiffuseMix(h ^ static_cast<uint32_t>(s >> 32) ^ 0x85ebca6bu);
  h = DiffuseMix(h ^ stream);
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

// ---- the paper's functions ---------------------------------------------------------------------------
/// Phi: the value's share of [lo, hi], clamped to [0, 1] [IAAT12 eq. 1].
SPHXR_HD SPHXR_INLINE float DiffusePotential(float value, float lo, float hi) {
  return (AtMost(value, hi) - AtMost(value, lo)) / (hi - lo);
}

/// The kind (DiffuseKind as a float, velocity.w) of a diffuse particle with `neighbours` fluid neighbours.
SPHXR_HD SPHXR_INLINE float DiffuseKindFor(int neighbours, const DiffuseConstants& c) {
  if (neighbours < c.sprayBelow) return static_cast<float>(DiffuseKind::kSpray);
  if (neighbours > c.bubbleAbove) return static_cast<float>(DiffuseKind::kBubble);
  return static_cast<float>(DiffuseKind::kFoam);
}

/// The fluid around a point: its particles within the support and their velocity averaged with the
/// kernel (Shepard), v~_f of [IAAT12 eq. 10] (zero without neighbours).
struct DiffuseSurroundings {
  int neighbours = 0;
  Vec3 velocity;
};
SPHXR_HD SPHXR_INLINE DiffuseSurroundings SurroundingsOf(const GridView& grid, const Vec4* fluidPosition,
                                                         const Vec4* fluidVelocity, const CubicSpline& kernel, Vec3 x) {
  DiffuseSurroundings s;
  Vec3 sum;
  float weight = 0.0f;
  ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluidPosition, x, [&](uint32_t j, Vec3 d) {
    const float r2 = Dot(d, d);
    if (r2 >= kernel.H2) return;
    const float w = kernel.W(sqrtf(r2));
    ++s.neighbours;
    sum += Xyz(fluidVelocity[j]) * w;
    weight += w;
  });
  if (weight > 0.0f) s.velocity = sum * (1.0f / weight);
  return s;
}

/// The fluid where the step left it, in the diffuse grid's order (DiffusePool sorts its own copy: the
/// fluid's order is not touched), and what the stages below write per fluid particle.
struct DiffuseFluidView {
  const Vec4* position;    // sorted copy
  const Vec4* velocity;    // sorted copy
  const uint32_t* id;      // the fluid particles' ids (the random numbers' key)
  Vec4* normal;            // xyz: unit outward normal (0 where the colour field has no gradient); w: fluid neighbours
  uint32_t* spawn;         // diffuse particles spawned this step
  const uint32_t* offset;  // exclusive prefix sum of spawn: the first slot of each one's spawns
  int count;
};

/// A buffer of the pool: positions (w: lifetime left, s), velocities (w: kind), and per particle 1 while alive.
struct DiffusePoolView {
  Vec4* position;
  Vec4* velocity;
  uint32_t* alive;
  int count;
};

/// Whether a fluid particle has kinetic energy above tau_k min: only those spawn [IAAT12 eq. 8].
struct DiffuseEnergetic {
  float twiceEnergyMin;  // 2 tau_k min, compared with |v|^2
  SPHXR_HD bool operator()(const Vec4& v) const { return v.x * v.x + v.y * v.y + v.z * v.z > twiceEnergyMin; }
};

/// Per cell of the diffuse grid: 1 when one of its fluid particles is energetic (DiffuseEnergetic), so
/// that the normals are computed only around those (a particle's neighbours lie in its 27 cells).
struct DiffuseCellFlagStage {
  const uint32_t* start;
  const uint32_t* end;
  const Vec4* velocity;  // sorted copy
  DiffuseEnergetic energetic;
  uint8_t* flag;
  SPHXR_HD void operator()(int c) const {
    uint8_t any = 0;
    if (start[c] != kEmptyCell) {
      for (uint32_t j = start[c]; j < end[c] && !any; ++j) any = energetic(velocity[j]) ? 1 : 0;
    }
    flag[c] = any;
  }
};

/// Each fluid particle's colour-field normal n_i = -sum_j V grad W_ij (normalised; outward at the
/// surface) and its count of fluid neighbours within the support; only where one of the 27 cells
/// around it holds an energetic particle (`cellFlag`): the others' normals are never read.
struct DiffuseNormalStage {
  GridView grid;
  DiffuseFluidView fluid;
  Physics ph;
  const uint8_t* cellFlag;
  SPHXR_HD void operator()(int i) const {
    const Vec3 xi = Xyz(fluid.position[i]);
    int cx, cy, cz;
    grid.CellOf(xi, &cx, &cy, &cz);
    bool needed = false;
    ForEachCellAround(grid, cx, cy, cz, [&](uint32_t c) { needed = needed || cellFlag[c] != 0; });
    if (!needed) {
      fluid.normal[i] = Vec4{};
      return;
    }
    Vec3 grad;
    int neighbours = 0;
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, xi, [&](uint32_t j, Vec3 xij) {
      const float r2 = Dot(xij, xij);
      if (j == static_cast<uint32_t>(i) || r2 >= ph.kernel.H2) return;
      ++neighbours;
      grad += xij * ph.kernel.GradFactor(sqrtf(r2));
    });
    const Vec3 n = grad * -ph.volume;
    const float length = Length(n);
    // (below a thousandth of 1/h the direction is rounding noise: no normal)
    const Vec3 unit = length * ph.kernel.H > 1e-3f ? n * (1.0f / length) : Vec3{};
    fluid.normal[i] = MakeVec4(unit, static_cast<float>(neighbours));
  }
};

/// At most this many spawns per fluid particle and step (so that the pool's 32-bit prefix sums hold four
/// million fluid particles; the paper's k_ta + k_wc give at most 600 at a 90 Hz step).
inline constexpr float kMaxSpawnsPerStep = 1024.0f;

/// How many diffuse particles fluid particle i spawns this step: n_d of [IAAT12 eq. 8], rounded down
/// after adding a uniform draw, so that its expectation is n_d at any step size.
struct DiffuseSpawnCountStage {
  GridView grid;
  DiffuseFluidView fluid;
  Physics ph;
  float dt;
  SPHXR_HD void operator()(int i) const {
    const DiffuseConstants& c = ph.diffuse;
    const Vec3 xi = Xyz(fluid.position[i]);
    const Vec3 vi = Xyz(fluid.velocity[i]);
    const float energy = 0.5f * Dot(vi, vi);
    const float ik = DiffusePotential(energy, c.energyMin, c.energyMax);  // [eq. 7]
    if (!(ik > 0.0f)) {  // n_d = 0 whatever the other potentials (and no neighbour scan)
      fluid.spawn[i] = 0;
      return;
    }
    const Vec4 own = fluid.normal[i];
    const Vec3 ni = Xyz(own);
    const bool surface = own.w <= static_cast<float>(c.bubbleAbove) && Dot(ni, ni) > 0.0f;
    const float h = ph.kernel.H;
    float trapped = 0.0f, curvature = 0.0f;
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, xi, [&](uint32_t j, Vec3 xij) {
      const float r2 = Dot(xij, xij);
      if (j == static_cast<uint32_t>(i) || r2 >= ph.kernel.H2 || !(r2 > 0.0f)) return;
      const float r = sqrtf(r2);
      const float w = 1.0f - r / h;  // W~ [eq. 3]
      const Vec3 vij = vi - Xyz(fluid.velocity[j]);
      const float speed = Length(vij);
      if (speed > 0.0f) trapped += speed * (1.0f - Dot(vij, xij) / (speed * r)) * w;  // [eq. 2]
      // x^_ji . n^_i < 0: j lies behind i's surface (the crest is convex there)           [eq. 4]
      if (surface && Dot(xij, ni) > 0.0f) curvature += (1.0f - Dot(ni, Xyz(fluid.normal[j]))) * w;
    });
    const float along = Dot(vi, ni) / sqrtf(2.0f * energy);  // v^_i . n^_i (energy > 0 here)
    const float delta = along >= 0.6f ? 1.0f : 0.0f;         // [eq. 6]
    const float ita = DiffusePotential(trapped, c.trappedAirMin, c.trappedAirMax);
    const float iwc = DiffusePotential(delta * curvature, c.waveCrestMin, c.waveCrestMax);
    const float expected = AtMost(ik * (c.trappedAir * ita + c.waveCrest * iwc) * dt, kMaxSpawnsPerStep);  // [eq. 8]
    fluid.spawn[i] = static_cast<uint32_t>(expected + DiffuseUniform(fluid.id[i], ph.step, 0u));
  }
};

/// Writes fluid particle i's spawns into the pool at first + offset_i + k, as long as that is below
/// first + room (the pool is full beyond), each sampled in the cylinder it swept [IAAT12 sec. 4.1]:
/// r = r_V sqrt(X_r), theta = 2 pi X_theta, h = X_h |dt v_i|; x = x_i + r cos(theta) e1 + r sin(theta) e2
/// + h v^_i, v = v_i + r cos(theta) e1 + r sin(theta) e2 (the paper's lateral spread, m taken as m/s),
/// with e1, e2 unit and orthogonal to v_i. Its kind is classified where it is born.
struct DiffuseEmitStage {
  GridView grid;
  DiffuseFluidView fluid;
  DiffusePoolView pool;
  Physics ph;
  float dt;
  uint32_t first;  // the first free slot
  uint32_t room;   // slots free after it
  SPHXR_HD void operator()(int i) const {
    const uint32_t spawns = fluid.spawn[i];
    const uint32_t begin = fluid.offset[i];
    if (spawns == 0 || begin >= room) return;
    const DiffuseConstants& c = ph.diffuse;
    const Vec3 xf = Xyz(fluid.position[i]);
    const Vec3 vf = Xyz(fluid.velocity[i]);
    const float speed = Length(vf);  // > 0: a particle at rest has no kinetic energy and spawns nothing
    const Vec3 axis = vf * (1.0f / speed);
    const Vec3 helper = axis.x * axis.x < 0.81f ? Vec3{1.0f, 0.0f, 0.0f} : Vec3{0.0f, 1.0f, 0.0f};
    Vec3 e1 = Cross(axis, helper);
    e1 = e1 * (1.0f / Length(e1));
    const Vec3 e2 = Cross(axis, e1);
    const uint32_t id = fluid.id[i];
    for (uint32_t k = 0; k < spawns && begin + k < room; ++k) {
      const uint32_t stream = 1u + 4u * k;
      const float r = c.radius * sqrtf(DiffuseUniform(id, ph.step, stream));
      const float theta = 6.28318530718f * DiffuseUniform(id, ph.step, stream + 1u);
      const float along = DiffuseUniform(id, ph.step, stream + 2u) * dt * speed;
      const float life = c.lifetime * (0.5f + 0.5f * DiffuseUniform(id, ph.step, stream + 3u));
      const Vec3 lateral = e1 * (r * cosf(theta)) + e2 * (r * sinf(theta));
      const Vec3 x = xf + lateral + axis * along;
      const DiffuseSurroundings s = SurroundingsOf(grid, fluid.position, fluid.velocity, ph.kernel, x);
      const uint32_t slot = first + begin + k;
      pool.position[slot] = MakeVec4(x, life);
      pool.velocity[slot] = MakeVec4(vf + lateral, DiffuseKindFor(s.neighbours, c));
    }
  }
};

/// One step of a diffuse particle [IAAT12 eq. 10-12]: classified by the fluid around it where the step
/// left the fluid, moved by its kind's rule, aged when foam, and alive = 0 once its lifetime is spent
/// or it has left the tank (an open tank has no lid: spray may fly above its rim and fall back).
struct DiffuseAdvectStage {
  GridView grid;
  const Vec4* fluidPosition;  // the diffuse grid's sorted copy
  const Vec4* fluidVelocity;
  DiffusePoolView pool;
  Physics ph;
  float dt;
  SPHXR_HD void operator()(int i) const {
    const DiffuseConstants& c = ph.diffuse;
    const Vec4 p = pool.position[i];
    const Vec3 x = Xyz(p);
    const DiffuseSurroundings s = SurroundingsOf(grid, fluidPosition, fluidVelocity, ph.kernel, x);
    const float kind = DiffuseKindFor(s.neighbours, c);
    Vec3 v = Xyz(pool.velocity[i]);
    float life = p.w;
    if (kind == static_cast<float>(DiffuseKind::kSpray)) {
      v += ph.gravity * dt;  // ballistic [eq. 11]
    } else if (kind == static_cast<float>(DiffuseKind::kBubble)) {
      v += ph.gravity * (-c.buoyancy * dt) + (s.velocity - v) * c.drag;  // buoyancy and drag [eq. 12]
    } else {
      v = s.velocity;  // carried by the water [eq. 10]
      life -= dt;      // only foam dissolves
    }
    const Vec3 to = x + v * dt;
    const Vec3& lo = ph.domainMin;
    const Vec3& hi = ph.domainMax;
    const bool inside =
        to.x >= lo.x && to.x <= hi.x && to.y >= lo.y && (!ph.closedTop || to.y <= hi.y) && to.z >= lo.z && to.z <= hi.z;
    pool.position[i] = MakeVec4(to, life);
    pool.velocity[i] = MakeVec4(v, kind);
    pool.alive[i] = life > 0.0f && inside ? 1u : 0u;
  }
};

/// Compaction of the pool in its order (oldest first): survivor i goes to rank_i - drop, and the
/// `drop` oldest survivors are retired to make room for this step's spawns.
struct DiffuseKeepStage {
  DiffusePoolView from;
  const uint32_t* rank;  // exclusive prefix sum of from.alive
  Vec4* toPosition;
  Vec4* toVelocity;
  uint32_t drop;
  SPHXR_HD void operator()(int i) const {
    if (from.alive[i] == 0u || rank[i] < drop) return;
    toPosition[rank[i] - drop] = from.position[i];
    toVelocity[rank[i] - drop] = from.velocity[i];
  }
};

}  // namespace sphxr::sim
