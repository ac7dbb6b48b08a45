// Position-based fluids (solvers/pbf.h, Macklin & Müller 2013) over a long violent run: ten simulated
// seconds of a dam break thrown at the far wall, without a NaN or a lost particle. (Martin & Moyce under
// PBF: dam_break_test.cpp; still water and the iteration extremes over one second: tests/sim/pbf_test.cpp;
// the held paddle and the 5 m/s swing: tests/interaction/paddle_test.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr {
namespace {

/// Kinetic plus potential energy of the fluid (J), the floor y = 0 as the potential's zero.
double MechanicalEnergy(const sim::HostFluid& f, double mass, double g) {
  double e = 0.0;
  for (size_t i = 0; i < f.size(); ++i) {
    const sim::Vec4& v = f.velocity[i];
    e += mass * (0.5 * (v.x * v.x + v.y * v.y + v.z * v.z) + g * f.position[i].y);
  }
  return e;
}

/// DFSPH's violent case (dfsph_validation_test.cpp) at `spacing`: the small dam break's column thrown
/// down and forward at 3 m/s, at PBF's defaults (3 substeps of a 90 Hz frame, 3.7 ms a step, 3
/// iterations). It hits the far wall within 0.1 s and sloshes for ten seconds (2,700 steps): no NaN, no
/// particle lost or out of the tank, and, since nothing drives the water after the throw and the walls
/// are still, less mechanical energy at the end than at the start (a solve that feeds energy into the
/// water fails).
void TenSecondsOfAViolentDamBreak(float spacing) {
  sim::SceneSetup scene = test::SmallDamBreak(spacing);
  scene.method = sim::SolverMethod::kPbf;
  scene.fluid[0].velocity = sim::Vec3{3.0f, -1.0f, 0.0f};
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const int n = solver->FluidCount();
  const double g = 9.81, mass = solver->ParticleMass();
  const double e0 = MechanicalEnergy(test::DownloadFluid(*solver), mass, g);
  float maxSpeed = 0.0f;
  while (solver->Time() < 10.0) {
    ASSERT_TRUE(solver->Step().ok()) << "t = " << solver->Time();
    const float v = solver->LastStep().maxSpeed;
    ASSERT_TRUE(std::isfinite(v)) << "non-finite at t = " << solver->Time();
    maxSpeed = std::max(maxSpeed, v);
  }
  const sim::HostFluid f = test::DownloadFluid(*solver);
  EXPECT_EQ(test::FirstNonFinite(f), "");
  EXPECT_EQ(static_cast<int>(f.size()), n) << "particles lost";
  for (const sim::Vec4& x : f.position) {
    ASSERT_TRUE(x.x >= scene.tank.min.x && x.x <= scene.tank.max.x && x.y >= scene.tank.min.y &&
                x.z >= scene.tank.min.z && x.z <= scene.tank.max.z)
        << "a particle left the tank at (" << x.x << ", " << x.y << ", " << x.z << ")";
  }
  const double e10 = MechanicalEnergy(f, mass, g);
  EXPECT_LT(e10, e0) << "mechanical energy " << e10 << " J at 10 s, " << e0 << " J at the start";
  const sim::Totals& totals = solver->GetTotals();
  ::testing::Test::RecordProperty("energy_ratio", std::to_string(e10 / e0));
  ::testing::Test::RecordProperty("max_speed_m_s", std::to_string(maxSpeed));
  std::printf("pbf violent dam break: %d particles, %lld steps, max speed %.2f m/s, energy %.4f -> %.4f J, "
              "%lld clamps\n",
              n, static_cast<long long>(totals.steps), maxSpeed, e0, e10, static_cast<long long>(totals.clampedEvents));
}

TEST(PbfExtremes, TenSecondsOfAViolentDamBreak) {
  // 900 particles (1 cm, the column moves 1.1 spacings a step), a few seconds on one core.
  TenSecondsOfAViolentDamBreak(0.01f);
}

// At half the spacing (7,200 particles, 2.2 spacings a step; about 75 s on one core) three iterations do
// not hold the impact on the far wall. Measured: no NaN, nothing lost or out of the tank, but the
// mechanical energy is 3.0 E0 at 0.1 s and 15.6 J against 5.16 J at 10 s, the mean compression 30-60 %
// throughout, speeds up to 96 m/s (pbf_max_speed, 20 m/s, caps only the prediction v*, not the velocity
// the corrections give). With 20 iterations the energy still rises to 1.3 E0 at the impact, then falls
// (0.044 E0 at 1 s; the ten seconds not run). s_corr off: the same as with it. docs/dev/physics.md, PBF.
TEST(PbfExtremes, DISABLED_TenSecondsOfAViolentDamBreakAtHalfTheSpacing) { TenSecondsOfAViolentDamBreak(0.005f); }

}  // namespace
}  // namespace sphxr
