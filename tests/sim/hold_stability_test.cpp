// The solver's integrator (IntegrateStage, sim/src/stages.h) with an acceleration computed once and
// held for k steps, as activity-based reuse holds it, against the analytic k-step map of one sound
// mode x'' = -w^2 x (docs/design/impulse_hold.md, why the held acceleration was retired):
//   x_k = (1 - (w dt)^2 k(k+1)/2) x_0 + k u_0,   u_k = -k (w dt)^2 x_0 + u_0,   u = v dt,
// whose determinant 1 + (w dt)^2 k(k-1)/2 exceeds 1 for every k >= 2. If the integrator changes (to
// velocity Verlet, say), these tests fail and the page's argument must be redone. The impulse hold,
// the hold the solver uses, is checked against its own map below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sphxr/sim/fields.h"
#include "stages.h"

namespace sphxr::sim {
namespace {

// One particle moving along x under the real IntegrateStage.
struct OneParticle {
  HostFluid host;
  Physics ph{};
  float dt;

  explicit OneParticle(float step) : dt(step) {
    host.resize(1);
    ph.domainMin = Vec3{-1e6f, -1e6f, -1e6f};
    ph.domainMax = Vec3{1e6f, 1e6f, 1e6f};
  }
  FluidView View() {
    FluidView v{};
#define SPHXR_TEST_VIEW(type, name) v.name = host.name.data();
    SPHXR_FLUID_FIELDS(SPHXR_TEST_VIEW)
#undef SPHXR_TEST_VIEW
    v.count = 1;
    return v;
  }
  // One reuse cycle: compute a = -w^2 x, then k steps of the integrator with it held.
  void Cycle(double w, int k) {
    host.acceleration[0] = Vec4{static_cast<float>(-w * w * host.position[0].x), 0.0f, 0.0f, 0.0f};
    const IntegrateStage stage{View(), ph, dt};
    for (int s = 0; s < k; ++s) stage(0);
  }
  // The same cycle under the impulse hold (IDLE = k - 1): the particle computes
  // and goes inactive (IC = IDLE), then reuses for IDLE steps (IC = IDLE - 1 ... 0), as ActivityStage
  // leaves the idle counts before each integration.
  void ImpulseCycle(double w, int k) {
    ph.reuseEnabled = true;
    ph.reuseIdle = k - 1;
    host.acceleration[0] = Vec4{static_cast<float>(-w * w * host.position[0].x), 0.0f, 0.0f, 0.0f};
    const IntegrateStage stage{View(), ph, dt};
    for (int s = 0; s < k; ++s) {
      host.idle[0] = k - 1 - s;
      stage(0);
    }
  }
};

// The k-step map measured on the integrator, columns from (x, u) = (1, 0) and (0, 1).
void MeasuredMap(double wdt, int k, double m[2][2], bool impulse = false) {
  const float dt = 1e-3f;
  const double w = wdt / dt;
  for (int col = 0; col < 2; ++col) {
    OneParticle p(dt);
    p.host.position[0] = Vec4{col == 0 ? 1.0f : 0.0f, 0.0f, 0.0f, 0.0f};
    p.host.velocity[0] = Vec4{col == 1 ? 1.0f / dt : 0.0f, 0.0f, 0.0f, 0.0f};
    if (impulse) {
      p.ImpulseCycle(w, k);
    } else {
      p.Cycle(w, k);
    }
    m[0][col] = p.host.position[0].x;
    m[1][col] = static_cast<double>(p.host.velocity[0].x) * dt;
  }
}

TEST(HoldStability, IntegratorMatchesTheAnalyticMapAndItsDeterminant) {
  for (double wdt : {1.0, 0.5, 1.0 / 3.0, 0.1}) {
    for (int k : {1, 2, 4}) {
      double m[2][2];
      MeasuredMap(wdt, k, m);
      const double w2 = wdt * wdt;
      const double expect[2][2] = {{1.0 - w2 * k * (k + 1) / 2.0, static_cast<double>(k)}, {-k * w2, 1.0}};
      for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 2; ++c) {
          EXPECT_NEAR(m[r][c], expect[r][c], 1e-4 * (1.0 + std::fabs(expect[r][c])))
              << "w dt " << wdt << ", k " << k << ", entry " << r << c;
        }
      }
      const double det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
      EXPECT_NEAR(det, 1.0 + w2 * k * (k - 1) / 2.0, 1e-3 * det) << "w dt " << wdt << ", k " << k;
      if (k >= 2) {
        EXPECT_GT(det, 1.0 + 0.5 * w2) << "holding for k >= 2 steps must expand phase space";
      }
    }
  }
}

// The consequence, run long: reuse off (k = 1) keeps a mode bounded at w dt = 1, IDLE 3 (k = 4)
// grows by the map's largest eigenvalue, 7 per cycle (the other is -1).
TEST(HoldStability, HoldingForFourStepsGrowsAModeThatReuseOffKeepsBounded) {
  const float dt = 1e-3f;
  const double w = 1.0 / dt;
  auto amplitude = [&](int k, int steps) {
    OneParticle p(dt);
    p.host.position[0] = Vec4{1e-6f, 0.0f, 0.0f, 0.0f};
    double peak = 0.0;
    for (int s = 0; s < steps; s += k) {
      p.Cycle(w, k);
      peak = std::max(peak, std::fabs(static_cast<double>(p.host.position[0].x)));
    }
    return peak / 1e-6;
  };
  const double off = amplitude(1, 400);
  const double held = amplitude(4, 20);  // 5 cycles
  EXPECT_LT(off, 3.0) << "symplectic Euler at w dt = 1 is stable";
  EXPECT_GT(held, 0.5 * std::pow(7.0, 5)) << "5 cycles of the x7 eigenvalue";
  EXPECT_LT(held, 20.0 * std::pow(7.0, 5));
}

// The impulse hold (docs/design/impulse_hold.md): kick k dt a on the computing step, then drift.
// Its k-step map is symplectic Euler at the step k dt, x_k = (1 - k^2 (w dt)^2) x_0 + k u_0,
// u_k = -k (w dt)^2 x_0 + u_0, with determinant exactly 1 (no phase-space growth) for every k.
TEST(HoldStability, ImpulseHoldIsSymplecticEulerAtTheHeldStep) {
  for (double wdt : {0.5, 1.0 / 3.0, 0.1}) {
    for (int k : {1, 2, 4}) {
      double m[2][2];
      MeasuredMap(wdt, k, m, true);
      const double w2 = wdt * wdt;
      const double expect[2][2] = {{1.0 - w2 * k * k, static_cast<double>(k)}, {-k * w2, 1.0}};
      for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 2; ++c) {
          EXPECT_NEAR(m[r][c], expect[r][c], 1e-4 * (1.0 + std::fabs(expect[r][c])))
              << "w dt " << wdt << ", k " << k << ", entry " << r << c;
        }
      }
      const double det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
      EXPECT_NEAR(det, 1.0, 1e-3) << "w dt " << wdt << ", k " << k;
    }
  }
}

// Where that map is stable (k w dt < 2) the impulse hold keeps a mode bounded that the held
// acceleration grows: w dt = 0.4, k = 4 (IDLE 3), 100 cycles. The held map's determinant is
// 1 + 0.16 * 6 = 1.96 per cycle; symplectic Euler at k w dt = 1.6 keeps the amplitude within
// 1 / sqrt(1 - (1.6 / 2)^2) = 1.67 of its start, times the initial phase's factor.
TEST(HoldStability, ImpulseHoldKeepsBoundedAModeThatTheHeldAccelerationGrows) {
  const float dt = 1e-3f;
  const double w = 0.4 / dt;
  auto amplitude = [&](bool impulse) {
    OneParticle p(dt);
    p.host.position[0] = Vec4{1e-6f, 0.0f, 0.0f, 0.0f};
    double peak = 0.0;
    for (int c = 0; c < 100; ++c) {
      if (impulse) {
        p.ImpulseCycle(w, 4);
      } else {
        p.Cycle(w, 4);
      }
      peak = std::max(peak, std::fabs(static_cast<double>(p.host.position[0].x)));
    }
    return peak / 1e-6;
  };
  const double impulse = amplitude(true);
  const double held = amplitude(false);
  EXPECT_LT(impulse, 3.0) << "the impulse hold at k w dt = 1.6";
  EXPECT_GT(held, 1e6) << "the held acceleration at the same step";
}

}  // namespace
}  // namespace sphxr::sim
