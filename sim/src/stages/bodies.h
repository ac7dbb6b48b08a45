#pragma once
// Moving boundaries (kinematic rigid bodies: paddles), host+device functors launched by backend_impl.h.
//
// Each step, for every body (BodyState, uploaded by the solver):
//   a. place:    boundary particles from the body frame to the start-of-step pose, x = c + R r, with the
//                rigid velocity v + w x (R r); sorted by cell like the fluid, own cell ranges
//   b. near:     per-cell flag "a moving boundary particle in the 27 cells" over the body's bounding box
//   (density and forces then add the bodies' terms for flagged cells, with the relative velocity;
//    ActivityStage keeps flagged particles active)
//   c. reaction: per body particle, minus the force it exerted on each fluid neighbour (the same pair
//                term as ForceStage): the fluid's force on the body, summed on the host per body
//   d. push-out: after integration, a fluid particle whose centre is inside a body's solid (at the end
//                -of-step pose) is moved out along the solid's normal to a quarter spacing outside, and
//                its velocity towards the solid (relative to it) removed
#include <cstdint>

#include "sphxr/sim/rigid.h"
#include "stages/grid.h"
#include "stages/views.h"

namespace sphxr::sim {

/// One body during one step (world frame).
struct BodyState {
  Vec3 position;        // origin at the start of the step
  Quat orientation;     // at the start of the step
  Vec3 velocity;        // m/s of the origin during the step
  Vec3 angular;         // rad/s during the step
  Vec3 endPosition;     // pose at the end of the step (push-out)
  Quat endOrientation;
  float boundRadius;    // every point of the solid and every boundary particle is this close to the origin
  int firstShape;       // primitives [firstShape, firstShape + shapeCount) of the shape array
  int shapeCount;
};

// a. canonical body particle i (body frame, w = Psi) -> cell code at the start pose
struct BodyCellStage {
  GridView grid;
  const BodyState* states;
  const Vec4* local;
  const uint32_t* bodyOf;
  uint32_t* keys;
  uint32_t* order;
  SPHXR_HD void operator()(int i) const {
    const BodyState& s = states[bodyOf[i]];
    const Vec3 x = s.position + Rotate(s.orientation, Xyz(local[i]));
    int cx, cy, cz;
    grid.CellOf(x, &cx, &cy, &cz);
    keys[i] = MortonEncode(static_cast<uint32_t>(cx), static_cast<uint32_t>(cy), static_cast<uint32_t>(cz));
    order[i] = static_cast<uint32_t>(i);
  }
};

// a. sorted slot s <- canonical particle order[s]: world position (w = Psi), rigid velocity (w = alpha)
struct BodyPlaceStage {
  const BodyState* states;
  const Vec4* local;
  const uint32_t* bodyOf;
  const float* alpha;
  const uint32_t* order;
  Vec4* position;
  Vec4* velocity;
  uint32_t* sortedBodyOf;
  SPHXR_HD void operator()(int slot) const {
    const uint32_t i = order[slot];
    const uint32_t b = bodyOf[i];
    const BodyState& s = states[b];
    const Vec4 l = local[i];
    const Vec3 r = Rotate(s.orientation, Xyz(l));
    position[slot] = MakeVec4(s.position + r, l.w);
    velocity[slot] = MakeVec4(s.velocity + Cross(s.angular, r), alpha[i]);
    sortedBodyOf[slot] = b;
  }
};

// b. cells of the box [lo, lo + dims) get the flag "a body particle in my 27 cells"
struct MovingNearStage {
  GridView grid;
  int lo[3];
  int dims[3];
  uint8_t* out;
  SPHXR_HD void operator()(int k) const {
    const int cx = lo[0] + k % dims[0], cy = lo[1] + (k / dims[0]) % dims[1], cz = lo[2] + k / (dims[0] * dims[1]);
    uint8_t near = 0;
    ForEachCellAround(grid, cx, cy, cz, [&](uint32_t n) {
      if (grid.bodyStart[n] != kEmptyCell) near = 1;
    });
    out[grid.Linear(cx, cy, cz)] = near;
  }
  int Items() const { return dims[0] * dims[1] * dims[2]; }

  /// The cells of a body's bounding sphere (centre, radius r), grown by one cell and cut to the grid.
  static MovingNearStage Around(const GridView& g, Vec3 centre, float r, uint8_t* out) {
    int lo[3], hi[3];
    g.CellOf(centre - Vec3{r, r, r}, &lo[0], &lo[1], &lo[2]);
    g.CellOf(centre + Vec3{r, r, r}, &hi[0], &hi[1], &hi[2]);
    const int top[3] = {g.nx - 1, g.ny - 1, g.nz - 1};
    MovingNearStage stage{g, {}, {}, out};
    for (int a = 0; a < 3; ++a) {
      stage.lo[a] = lo[a] > 0 ? lo[a] - 1 : 0;
      stage.dims[a] = (hi[a] < top[a] ? hi[a] + 1 : top[a]) - stage.lo[a] + 1;
    }
    return stage;
  }
};

// c. force of the fluid on body particle b: minus the sum of what b added to each fluid neighbour's
// acceleration (times the particle mass). Same pair term as ForceStage (BodyAcceleration), evaluated from
// the fluid particle's side, so action and reaction are equal and opposite to rounding.
struct BodyReactionStage {
  GridView grid;
  FluidView fluid;
  Physics ph;
  const float* bodyPressureTerm;  // written by ForceStage for every fluid particle near a body
  Vec4* force;                    // per sorted body particle, N
  SPHXR_HD void operator()(int b) const {
    const Vec4 xb = grid.body[b];
    const Vec4 vb = grid.bodyVelocity[b];
    const CubicSpline k = ph.kernel;
    const float h = ph.smoothing;
    const float eps = 0.01f * h * h;
    Vec3 f{0.0f, 0.0f, 0.0f};
    ForEachInCells(grid, grid.fluidStart, grid.fluidEnd, fluid.position, Xyz(xb), [&](uint32_t i, Vec3 dbi) {
      const float r2 = Dot(dbi, dbi);
      if (r2 >= k.H2 || r2 == 0.0f) return;
      const Vec3 d = -dbi;  // x_i - x_b
      const float rhoi = fluid.density[i];
      const float viscWall = ph.soundSpeed * h / (2.0f * rhoi);
      float term = ph.bodyGradScale * bodyPressureTerm[i];
      const float vx = Dot(Xyz(fluid.velocity[i]) - Xyz(vb), d);
      if (vx < 0.0f) term -= vb.w * viscWall * vx / (r2 + eps);
      // fluid i received a_i -= d Psi_b term gradFactor: the body gets + m d Psi_b term gradFactor.
      f += d * (ph.mass * xb.w * term * k.GradFactor(sqrtf(r2)));
    });
    force[b] = MakeVec4(f);
  }
};

// d. push-out (after integration, against the end-of-step pose)
struct PushOutStage {
  FluidView fluid;
  const BodyState* states;
  const ShapePrimitive* shapes;
  int bodyCount;
  float clearance;  // m outside the solid a pushed particle is put (a quarter spacing)
  SPHXR_HD void operator()(int i) const {
    Vec4 x = fluid.position[i];
    Vec4 v = fluid.velocity[i];
    bool pushed = false;
    for (int k = 0; k < bodyCount; ++k) {
      const BodyState& s = states[k];
      const Vec3 rel = Xyz(x) - s.endPosition;
      const float reach = s.boundRadius + clearance;
      if (Dot(rel, rel) > reach * reach) continue;
      const Quat inv = Conjugate(s.endOrientation);
      // Two passes: a particle pushed out of one primitive may land in another (blade on a handle).
      for (int pass = 0; pass < 2; ++pass) {
        const Vec3 p = Rotate(inv, Xyz(x) - s.endPosition);
        Vec3 nLocal;
        const float dist = UnionDistance(shapes + s.firstShape, s.shapeCount, p, &nLocal);
        if (dist >= 0.0f) break;
        const Vec3 n = Rotate(s.endOrientation, nLocal);
        const Vec3 moved = Xyz(x) + n * (clearance - dist);
        x = MakeVec4(moved, x.w);
        // No velocity into the solid relative to its surface velocity there.
        const Vec3 vBody = s.velocity + Cross(s.angular, moved - s.endPosition);
        const float vn = Dot(Xyz(v) - vBody, n);
        if (vn < 0.0f) v = MakeVec4(Xyz(v) - n * vn, v.w);
        pushed = true;
      }
    }
    if (!pushed) return;
    fluid.position[i] = x;
    fluid.velocity[i] = v;
    Vec4 a = fluid.acceleration[i];
    a.w = a.w == 1.0f ? 3.0f : 2.0f;  // StepReductionOp counts pushed particles
    fluid.acceleration[i] = a;
  }
};

}  // namespace sphxr::sim
