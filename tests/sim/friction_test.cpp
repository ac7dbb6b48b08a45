// Wall friction (tank.friction, docs/design/walls.md#friction). The sampler gives each wall particle
// its face's coefficient (checked against the particles' positions, not the sampler's loops), and the
// two physical choices do what their names say: a slab of water sliding along a no-slip floor has zero
// velocity at the face (the boundary condition itself), along a free-slip one it keeps its speed
// (nothing along the wall can take tangential momentum out of a uniform flow).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "sampling.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

TEST(Friction, EachWallParticleGetsItsFacesCoefficient) {
  SceneSetup s;
  s.params.spacing = 0.01f;
  s.params.viscosity = 0.05f;
  s.params.boundaryViscosity = 0.3f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.2f, 0.15f, 0.1f}};
  s.openTop = false;
  s.boundaryLayers = 2;
  s.obstacles.push_back({{0.08f, 0.0f, 0.03f}, {0.12f, 0.05f, 0.07f}});
  s.friction.floor = WallFriction::kNoSlip;
  s.friction.top = WallFriction::kFreeSlip;
  s.friction.xMin = WallFriction::kFreeSlip;
  s.friction.xMax = WallFriction::kArtificial;
  s.friction.zMin = s.friction.zMax = WallFriction::kFreeSlip;
  s.friction.obstacles = WallFriction::kNoSlip;
  const float noSlip = 4.0f * s.params.viscosity;  // the fluid pair term's mass form (2) x mirrored velocity (2)
  EXPECT_FLOAT_EQ(WallFrictionAlpha(s.params, WallFriction::kNoSlip), noSlip);
  EXPECT_FLOAT_EQ(WallFrictionAlpha(s.params, WallFriction::kFreeSlip), 0.0f);
  EXPECT_FLOAT_EQ(WallFrictionAlpha(s.params, WallFriction::kArtificial), 0.3f);

  std::vector<Vec4> boundary;
  std::vector<float> alpha;
  SampleBoundary(s, &boundary, &alpha);
  ASSERT_EQ(alpha.size(), boundary.size());
  int floor = 0, xMax = 0, obstacle = 0, freeSlip = 0;
  for (size_t b = 0; b < boundary.size(); ++b) {
    const Vec4 p = boundary[b];
    const bool inTank = p.x > s.tank.min.x && p.x < s.tank.max.x && p.y > s.tank.min.y && p.y < s.tank.max.y &&
                        p.z > s.tank.min.z && p.z < s.tank.max.z;
    float expected;
    if (inTank) {  // an obstacle's particle
      expected = noSlip;
      ++obstacle;
    } else {
      // Outside the tank: the faces it lies behind; an edge or a corner takes the largest coefficient.
      expected = 0.0f;
      if (p.y < s.tank.min.y) expected = std::max(expected, noSlip), ++floor;
      if (p.x > s.tank.max.x) expected = std::max(expected, 0.3f), ++xMax;
      if (expected == 0.0f) ++freeSlip;
    }
    EXPECT_FLOAT_EQ(alpha[b], expected) << "wall particle at " << p.x << ", " << p.y << ", " << p.z;
  }
  EXPECT_GT(floor, 0);
  EXPECT_GT(xMax, 0);
  EXPECT_GT(obstacle, 0);
  EXPECT_GT(freeSlip, 0);
}

// A slab 3 cm deep (6 or 12 spacings) and 30 cm long, at rest under gravity (its hydrostatic start),
// slides at U along x over the floor of a long tank between free-slip side walls for 0.1 s. Returns
// the mean x velocity of each of the two lowest particle layers over the slab's middle, which the
// collapse of its ends has not reached.
struct Profile {
  double first = 0.0, second = 0.0;  // layers at 0.5 and 1.5 spacings above the floor
};
Profile Slide(WallFriction floor, float u, float dx) {
  SceneSetup s;
  s.params.spacing = dx;
  s.params.stiffness = 20000.0f;  // c = 11.8 m/s, 60 x U
  s.params.viscosity = 0.1f;      // nu ~ alpha c h / 10 = 6e-4 m^2/s at 5 mm: a layer 2 sqrt(nu t) = 15 mm thick at 0.1 s
  s.params.boundaryViscosity = 0.0f;
  s.params.maxDt = 5e-4f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.45f, 0.1f, 0.03f}};
  s.boundaryLayers = 2;
  s.friction = TankFriction{floor, WallFriction::kFreeSlip, WallFriction::kFreeSlip, WallFriction::kFreeSlip,
                            WallFriction::kFreeSlip, WallFriction::kFreeSlip, WallFriction::kFreeSlip};
  const float x0 = 0.05f, length = 0.3f;
  s.fluid.push_back({{{x0, 0.0f, 0.0f}, {x0 + length, 0.03f, 0.03f}}, Vec3{u, 0.0f, 0.0f}, /*hydrostatic=*/true});
  std::unique_ptr<Solver> solver;
  EXPECT_TRUE(Solver::Create(s, ::sphxr::test::AllCoresConfig(), &solver).ok());
  if (!solver) return {};
  while (solver->Time() < 0.1) {
    EXPECT_TRUE(solver->Step().ok());
  }
  HostFluid host;
  solver->Download(&host);
  double sum[2] = {0.0, 0.0};
  int count[2] = {0, 0};
  const double shift = solver->Time() * u;  // the slab's middle moves with it (at most U)
  // The ends collapse under gravity; their news travels at sqrt(g depth) = 0.54 m/s, 5.4 cm in 0.1 s.
  const double margin = 0.07;
  for (size_t i = 0; i < host.size(); ++i) {
    const Vec4 p = host.position[i];
    const int layer = static_cast<int>(std::floor(p.y / dx));
    if (layer < 0 || layer > 1 || p.x < x0 + margin + shift || p.x > x0 + length - margin) continue;
    sum[layer] += host.velocity[i].x;
    ++count[layer];
  }
  EXPECT_GT(count[0], 20);
  EXPECT_GT(count[1], 20);
  return {sum[0] / std::max(1, count[0]), sum[1] / std::max(1, count[1])};
}

// The velocity at the face, extrapolated linearly from the two lowest layers (0.5 and 1.5 spacings up).
double AtFace(const Profile& p) { return p.first - 0.5 * (p.second - p.first); }

TEST(Friction, NoSlipHoldsTheWaterStillAtTheFaceAndConvergesWithTheSpacing) {
  const float u = 0.2f;
  const Profile coarse = Slide(WallFriction::kNoSlip, u, 0.005f);
  const Profile fine = Slide(WallFriction::kNoSlip, u, 0.0025f);
  // The wall took momentum: the lowest layer is well below U (free slip keeps it, the test below).
  EXPECT_LT(coarse.first, 0.5 * u);
  EXPECT_LT(fine.first, 0.5 * u);
  // Stokes' first problem, u(y) = U erf(y / (2 sqrt(nu t))), extrapolated the same way from 0.5 and
  // 1.5 spacings gives under 0.05 U at the face for a layer at least two spacings thick: a no-slip wall
  // reaches that, within a first-order error in the spacing. So at the finer spacing the face velocity
  // is under 0.1 U, and halving the spacing must cut it (first order: by half).
  EXPECT_LT(std::fabs(AtFace(fine)), 0.1 * u) << "layers " << fine.first << ", " << fine.second;
  EXPECT_LT(std::fabs(AtFace(fine)), 0.75 * std::fabs(AtFace(coarse)))
      << "face velocity " << AtFace(coarse) << " at 5 mm, " << AtFace(fine) << " at 2.5 mm";
}

TEST(Friction, FreeSlipKeepsTheSlabsSpeed) {
  const float u = 0.2f;
  const Profile p = Slide(WallFriction::kFreeSlip, u, 0.005f);
  // Nothing along the wall acts on a uniform flow: the fluid's own viscosity has no gradient to act on
  // and the wall's pressure is along its normal. What is left is the lattice's ripple as the layers
  // slide over the wall sheet, well under 5 % of U.
  EXPECT_NEAR(p.first, u, 0.05 * u);
  EXPECT_NEAR(p.second, u, 0.05 * u);
}

}  // namespace
}  // namespace sphxr::sim
