// Momentum conservation of the fluid-fluid interaction: without gravity and away from the walls, every
// fluid force is a pair force m_i m_j (...) grad W_ij, antisymmetric in i and j, so symplectic Euler
// keeps the total momentum (and, the pair forces being central, the angular momentum) up to rounding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sphxr/sim/measure.h"
#include "support.h"

namespace sphxr::sim {
namespace {

struct Angular {
  double lx = 0, ly = 0, lz = 0, scale = 0;  // sum x cross v (per unit mass), sum |x||v|
};

Angular AngularMomentum(const HostFluid& f, Vec3 centre) {
  Angular a;
  for (size_t i = 0; i < f.size(); ++i) {
    const double x = f.position[i].x - centre.x, y = f.position[i].y - centre.y, z = f.position[i].z - centre.z;
    const double vx = f.velocity[i].x, vy = f.velocity[i].y, vz = f.velocity[i].z;
    a.lx += y * vz - z * vy;
    a.ly += z * vx - x * vz;
    a.lz += x * vy - y * vx;
    a.scale += std::sqrt(x * x + y * y + z * z) * std::sqrt(vx * vx + vy * vy + vz * vz);
  }
  return a;
}

TEST(ConservationTest, MomentumOfCollidingBlocksInAClosedBox) {
  const float dx = 0.02f;
  SceneSetup scene = test::TankScene({0, 0, 0}, {1.2f, 0.8f, 0.6f}, dx);
  scene.openTop = false;
  scene.gravity = {0, 0, 0};
  // 8^3 = 512 particles each: A and B head-on along x, C from above with an off-axis velocity.
  const float v = 1.0f;
  scene.fluid.push_back(test::Block({0.30f, 0.20f, 0.20f}, {0.46f, 0.36f, 0.36f}, {v, 0, 0}));
  scene.fluid.push_back(test::Block({0.54f, 0.20f, 0.20f}, {0.70f, 0.36f, 0.36f}, {-v, 0, 0}));
  scene.fluid.push_back(test::Block({0.42f, 0.42f, 0.22f}, {0.58f, 0.58f, 0.38f}, {0.3f, -1.0f, 0.4f}));
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const int n = solver->FluidCount();
  ASSERT_EQ(n, 3 * 512);

  HostFluid f = test::DownloadFluid(*solver);
  const MomentumSummary p0 = Momentum(f);
  // independent expectation from the scene: 512 particles per block with the block's velocity
  EXPECT_NEAR(p0.px, 512.0 * (v - v + 0.3f), 1e-3);
  EXPECT_NEAR(p0.py, 512.0 * -1.0, 1e-3);
  EXPECT_NEAR(p0.pz, 512.0 * 0.4, 1e-3);
  const Vec3 centre{0.6f, 0.4f, 0.3f};
  const Angular l0 = AngularMomentum(f, centre);

  // The walls' boundary particles sit half a spacing outside the tank faces; no fluid particle may come
  // within the support of them, or wall forces (not momentum conserving) enter.
  const float H = solver->SupportRadius();
  const Aabb tank = scene.tank;
  const float keepOut = H + 0.5f * dx;
  auto wallDistance = [&](const HostFluid& h) {
    float d = 1e30f;
    for (const Vec4& x : h.position) {
      d = std::min({d, x.x - tank.min.x, tank.max.x - x.x, x.y - tank.min.y, tank.max.y - x.y, x.z - tank.min.z,
                    tank.max.z - x.z});
    }
    return d;
  };

  // A is ids [0, 512): its mean x velocity measures the collision.
  auto meanVxOfA = [&](const HostFluid& h) {
    double s = 0;
    for (size_t i = 0; i < h.size(); ++i)
      if (h.id[i] < 512) s += h.velocity[i].x;
    return s / 512.0;
  };

  const double endTime = 0.09;  // the gap of 0.08 m closes at 2 m/s after 0.04 s
  int steps = 0;
  double worstP = 0.0, worstL = 0.0;
  while (solver->Time() < endTime) {
    ASSERT_TRUE(solver->Step().ok());
    ++steps;
    ASSERT_LT(steps, 5000) << "time step collapsed: dt = " << solver->LastStep().dt;
    ASSERT_EQ(solver->LastStep().clamped, 0) << "particles clamped at step " << steps;
    f = test::DownloadFluid(*solver);
    ASSERT_EQ(static_cast<int>(f.size()), n);
    ASSERT_EQ(test::FirstNonFinite(f), "") << "at step " << steps;
    ASSERT_GT(wallDistance(f), keepOut) << "test precondition: a particle came within the support of a wall at step "
                                        << steps << " (t = " << solver->Time() << " s); shorten the run";
    const MomentumSummary p = Momentum(f);
    const double dp = std::sqrt((p.px - p0.px) * (p.px - p0.px) + (p.py - p0.py) * (p.py - p0.py) +
                                (p.pz - p0.pz) * (p.pz - p0.pz));
    worstP = std::max(worstP, dp / p0.sumAbs);
    ASSERT_LE(dp / p0.sumAbs, 1e-4) << "momentum drift at step " << steps << ": p = [" << p.px << ", " << p.py << ", "
                                    << p.pz << "], initially [" << p0.px << ", " << p0.py << ", " << p0.pz
                                    << "], sum|v|0 = " << p0.sumAbs;
    const Angular l = AngularMomentum(f, centre);
    const double dl = std::sqrt((l.lx - l0.lx) * (l.lx - l0.lx) + (l.ly - l0.ly) * (l.ly - l0.ly) +
                                (l.lz - l0.lz) * (l.lz - l0.lz));
    worstL = std::max(worstL, dl / l0.scale);
    ASSERT_LE(dl / l0.scale, 1e-4) << "angular momentum drift at step " << steps;
  }
  // The blocks did collide: A lost a good part of its x velocity, and the fluid was compressed.
  EXPECT_LT(meanVxOfA(f), 0.7 * v) << "blocks A and B did not interact; lengthen the run";
  EXPECT_EQ(solver->GetTotals().clampedEvents, 0);
  EXPECT_EQ(solver->GetTotals().steps, steps);
  RecordProperty("steps", steps);
  RecordProperty("worst_relative_momentum_drift", std::to_string(worstP));
  RecordProperty("worst_relative_angular_momentum_drift", std::to_string(worstL));
}

}  // namespace
}  // namespace sphxr::sim
