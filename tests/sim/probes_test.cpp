// Probes (sphxr/sim/probes.h) in the settled tank (tests/data/tank_rest_settled.state): still water at
// rest, so the truth is hydrostatics, p = rho0 g depth, with the depth from the free surface as the
// hydrostatic tests define it (the top particle's centre plus half a spacing). And the probe stage's
// sums against a brute-force host sum over every particle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "sphxr/app/scene_file.h"
#include "sphxr/app/state_file.h"
#include "sphxr/sim/probes.h"
#include "sphxr/sim/solver.h"
#include "kernel.h"
#include "support.h"

namespace sphxr::sim {
namespace {

struct Settled {
  app::SceneFile scene;
  std::unique_ptr<Solver> solver;
  float surface = 0.0f;  // m: the top particle's centre plus half a spacing
};

void LoadSettled(Settled* s) {
  ASSERT_TRUE(app::LoadScene(SPHXR_SCENES_DIR "/tank_rest.json", &s->scene).ok());
  const Status created = Solver::Create(s->scene.setup, ::sphxr::test::TestConfig(), &s->solver);
  ASSERT_TRUE(created.ok()) << created.message();
  app::StateFile state;
  const Status read = app::ReadStateFile(SPHXR_TEST_DATA_DIR "/tank_rest_settled.state", &state);
  ASSERT_TRUE(read.ok()) << read.message();
  const Status restored = app::RestoreState(state, s->solver.get());
  ASSERT_TRUE(restored.ok()) << restored.message();
  HostFluid h;
  s->solver->Download(&h);
  float top = -1e30f;
  for (const Vec4& p : h.position) top = std::max(top, p.y);
  s->surface = top + 0.5f * s->scene.setup.params.spacing;
}

// The tank is 0.2 x 0.3 x 0.1 m with water about 0.2 m deep; spacing 1 cm.
ProbeSet TankProbes() {
  ProbeSet set;
  // Points in the water, away from walls, at three depths.
  for (float y : {0.05f, 0.10f, 0.15f}) set.pressure.push_back({"mid", {0.1f, y, 0.05f}, {}, {}});
  // On the side walls' faces (x = 0 and x = 0.2) and on the floor, half a spacing into the water.
  set.pressure.push_back({"left", {0.0f, 0.08f, 0.05f}, {-1.0f, 0.0f, 0.0f}, {}});
  set.pressure.push_back({"right", {0.2f, 0.12f, 0.05f}, {1.0f, 0.0f, 0.0f}, {}});
  set.pressure.push_back({"floor", {0.1f, 0.0f, 0.05f}, {0.0f, -1.0f, 0.0f}, {}});
  // Above the water.
  set.pressure.push_back({"air", {0.1f, 0.25f, 0.05f}, {}, {}});
  set.pressure.push_back({"air_wall", {0.0f, 0.26f, 0.05f}, {-1.0f, 0.0f, 0.0f}, {}});
  set.level.push_back({"centre", 0.1f, 0.05f, {}, {}});
  set.level.push_back({"corner", 0.02f, 0.02f, {}, {}});
  set.level.push_back({"above", 0.1f, 0.05f, 0.24f, 0.3f});  // a line above the water: dry
  return set;
}

Vec3 PointOf(const PressureProbe& p, float dx) {
  return Length(p.normal) > 0.0f ? p.at - p.normal * p.offset.value_or(0.5f * dx) : p.at;
}

/// Sensors on the four side walls' faces every 2 cm of height, half a spacing into the water, and on
/// the floor.
ProbeSet WallSensors() {
  ProbeSet set;
  for (float y = 0.02f; y < 0.19f; y += 0.02f) {
    set.pressure.push_back({"x0", {0.0f, y, 0.05f}, {-1, 0, 0}, {}});
    set.pressure.push_back({"x1", {0.2f, y, 0.05f}, {1, 0, 0}, {}});
    set.pressure.push_back({"z0", {0.1f, y, 0.0f}, {0, 0, -1}, {}});
    set.pressure.push_back({"z1", {0.1f, y, 0.1f}, {0, 0, 1}, {}});
  }
  for (float x = 0.02f; x < 0.2f; x += 0.03f) set.pressure.push_back({"floor", {x, 0.0f, 0.05f}, {0, -1, 0}, {}});
  return set;
}

/// Sensors half a spacing from both side walls of each vertical edge of the tank, every 2 cm up to a
/// spacing under the surface, and half a spacing from the three faces of each floor corner.
ProbeSet CornerSensors(float dx, float surface) {
  const float h = 0.5f * dx, diagonal = std::sqrt(2.0f) * h, triple = std::sqrt(3.0f) * h;
  const float r2 = 1.0f / std::sqrt(2.0f), r3 = 1.0f / std::sqrt(3.0f);
  ProbeSet set;
  for (const Vec3 c : {Vec3{0.0f, 0.0f, 0.0f}, Vec3{0.2f, 0.0f, 0.0f}, Vec3{0.0f, 0.0f, 0.1f}, Vec3{0.2f, 0.0f, 0.1f}}) {
    const float sx = c.x > 0.0f ? 1.0f : -1.0f, sz = c.z > 0.0f ? 1.0f : -1.0f;
    set.pressure.push_back({"corner", c, {sx * r3, -r3, sz * r3}, triple});
    for (float y = 0.02f; y < surface - dx; y += 0.02f) {
      set.pressure.push_back({"edge", {c.x, y, c.z}, {sx * r2, 0.0f, sz * r2}, diagonal});
    }
  }
  return set;
}

// Still water: the wall sensors measure hydrostatics, a gauge reads the free surface within half a
// spacing, and probes above the water read dry. Hydrostatics as the validation measures it
// (tests/validation/hydrostatic_test.cpp): the least-squares slope of p against depth through the
// origin, here held to the 2 % target of rho0 g. Each single sensor is not held to 2 % here: the
// settled state's own pressure field stands +0.1 .. +3 % (and up to +11 % two spacings under the
// surface) off rho0 g depth around the sensors, which the disabled test below shows (the solver's
// pressure field, not the probes: their sums themselves are exact, the brute-force test).
TEST(Probes, StillWaterReadsHydrostaticsAndTheSurface) {
  Settled s;
  LoadSettled(&s);
  if (HasFatalFailure()) return;
  const SceneSetup& setup = s.scene.setup;
  const float dx = setup.params.spacing, rho0 = setup.params.restDensity, g = -setup.gravity.y;
  const ProbeSet walls = WallSensors();
  ProbeSample sample;
  const Status st = s.solver->SampleProbes(walls, &sample);
  ASSERT_TRUE(st.ok()) << st.message();
  double num = 0.0, den = 0.0;
  for (size_t k = 0; k < walls.pressure.size(); ++k) {
    const double depth = s.surface - PointOf(walls.pressure[k], dx).y;
    ASSERT_GT(depth, 0.0);
    ASSERT_FALSE(std::isnan(sample.pressure[k])) << walls.pressure[k].name << " at depth " << depth << " reads dry";
    num += sample.pressure[k] * depth;
    den += depth * depth;
  }
  std::printf("wall sensors: pressure gradient %.4f rho0 g (%zu sensors)\n", num / den / (rho0 * g), walls.pressure.size());
  EXPECT_NEAR(num / den / (rho0 * g), 1.0, 0.02) << "the wall sensors' pressure gradient relative to rho0 g";

  const ProbeSet set = TankProbes();
  ASSERT_TRUE(s.solver->SampleProbes(set, &sample).ok());
  for (size_t k = 0; k < set.pressure.size(); ++k) {
    const float depth = s.surface - PointOf(set.pressure[k], dx).y;
    if (depth < 0.0f) {
      EXPECT_TRUE(std::isnan(sample.pressure[k])) << set.pressure[k].name << ": above the water reads dry, not " << sample.pressure[k];
    } else {
      EXPECT_FALSE(std::isnan(sample.pressure[k])) << set.pressure[k].name << ": in the water reads wet";
    }
  }
  ASSERT_EQ(sample.level.size(), set.level.size());
  EXPECT_NEAR(sample.level[0], s.surface, 0.5f * dx);
  EXPECT_NEAR(sample.level[1], s.surface, 0.5f * dx);
  EXPECT_TRUE(std::isnan(sample.level[2])) << "a gauge above the water reads dry, not " << sample.level[2];
  EXPECT_DOUBLE_EQ(sample.time, s.solver->Time());
}

// The target: every probe in still water reads rho0 g depth within 2 %, the depth from the free
// surface as the hydrostatic tests define it. Disabled: the settled state (summation density) fails it,
// the sensors reading -4.2 .. +3.7 % off below 4 cm of depth and up to +11 % two spacings under the
// surface, points in the water +0.8 .. +4.8 %. Near the surface the Shepard average is biased deep (its
// kernel is cut by the surface, so its weights sit below the point); deeper, each particle's pressure
// carries the settled state's density scatter times c^2. The wall sensors' gradient (above) is within
// 2 % of rho0 g; a delta_sph settled state is not built yet (the settle sums the density).
TEST(Probes, DISABLED_StillWaterReadsRho0GDepthAtEveryProbe) {
  Settled s;
  LoadSettled(&s);
  if (HasFatalFailure()) return;
  const SceneSetup& setup = s.scene.setup;
  const float dx = setup.params.spacing, rho0 = setup.params.restDensity, g = -setup.gravity.y;
  ProbeSet set = WallSensors();
  for (const PressureProbe& p : TankProbes().pressure) set.pressure.push_back(p);
  ProbeSample sample;
  ASSERT_TRUE(s.solver->SampleProbes(set, &sample).ok());
  for (size_t k = 0; k < set.pressure.size(); ++k) {
    const float depth = s.surface - PointOf(set.pressure[k], dx).y;
    if (depth < 0.0f) continue;
    EXPECT_NEAR(sample.pressure[k], rho0 * g * depth, 0.02f * rho0 * g * depth)
        << set.pressure[k].name << " at depth " << depth;
  }
}

// The stage's sums against sums over every particle on the host, in double. Float sums of n terms in
// another order differ by at most about n eps times the sum of the terms' magnitudes.
TEST(Probes, StageAgreesWithBruteForceSums) {
  Settled s;
  LoadSettled(&s);
  if (HasFatalFailure()) return;
  const SceneSetup& setup = s.scene.setup;
  const float dx = setup.params.spacing;
  ProbeSet set = TankProbes();
  set.pressure.push_back({"surface", {0.1f, s.surface - 0.3f * dx, 0.05f}, {}, {}});  // a partial kernel
  for (const PressureProbe& p : CornerSensors(dx, s.surface).pressure) set.pressure.push_back(p);
  ProbeSample sample;
  ASSERT_TRUE(s.solver->SampleProbes(set, &sample).ok());
  HostFluid h;
  s.solver->Download(&h);
  const CubicSpline k = CubicSpline::Make(s.solver->SupportRadius());
  const double mass = s.solver->ParticleMass();
  auto sums = [&](Vec3 x, double* weighted, double* sum, double* magnitude, int* terms) {
    *weighted = *sum = *magnitude = 0.0;
    *terms = 0;
    for (size_t j = 0; j < h.size(); ++j) {
      const Vec3 d = x - Xyz(h.position[j]);
      const float r = Length(d);
      if (r >= k.H) continue;
      const double vw = mass / h.density[j] * k.W(r);
      *weighted += vw * h.pressure[j];
      *sum += vw;
      *magnitude += vw * std::fabs(h.pressure[j]);
      ++*terms;
    }
  };
  const double eps = 6e-8;  // float's unit roundoff
  for (size_t p = 0; p < set.pressure.size(); ++p) {
    SCOPED_TRACE(set.pressure[p].name);
    double weighted, sum, magnitude;
    int terms;
    sums(PointOf(set.pressure[p], dx), &weighted, &sum, &magnitude, &terms);
    EXPECT_NEAR(sample.shepard[p], sum, (terms + 2) * eps * sum + 1e-30);
    if (sum >= ProbeDryThreshold(PointOf(set.pressure[p], dx), setup.tank, setup.obstacles, s.solver->SupportRadius())) {
      ASSERT_FALSE(std::isnan(sample.pressure[p]));
      // p = weighted / sum: both sums' rounding, relative.
      const double bound = (terms + 2) * eps * (magnitude / sum + std::fabs(weighted / sum)) + 1e-6;
      EXPECT_NEAR(sample.pressure[p], weighted / sum, bound);
    } else {
      EXPECT_TRUE(std::isnan(sample.pressure[p]));
    }
  }
  // The gauges: the same walk (probes.h: coarse steps, the crossing's step in fine steps, linear
  // interpolation) over brute-force fractions.
  for (size_t q = 0; q < set.level.size(); ++q) {
    const LevelGauge& gauge = set.level[q];
    SCOPED_TRACE(gauge.name);
    auto phi = [&](float y) {
      double weighted, sum, magnitude;
      int terms;
      sums(Vec3{gauge.x, y, gauge.z}, &weighted, &sum, &magnitude, &terms);
      return sum;
    };
    const float bottom = gauge.bottom.value_or(setup.tank.min.y), top = gauge.top.value_or(setup.tank.max.y);
    const float coarse = kLevelCoarse * dx, fine = kLevelFine * dx;
    bool wet = phi(bottom) >= 0.5;
    double level = std::nan("");
    for (float y = bottom; y < top;) {
      const float yNext = std::min(y + coarse, top);
      if (!wet) {
        wet = phi(yNext) >= 0.5;
      } else if (phi(yNext) < 0.5) {
        for (float ya = y;;) {
          const float yb = std::min(ya + fine, yNext);
          if (phi(yb) < 0.5) {
            level = ya + (yb - ya) * (phi(ya) - 0.5) / (phi(ya) - phi(yb));
            break;
          }
          ya = yb;
        }
        break;
      }
      y = yNext;
      if (y >= top && wet) level = top;
    }
    if (std::isnan(level)) {
      EXPECT_TRUE(std::isnan(sample.level[q]));
    } else {
      // The fractions' rounding moves the interpolated crossing by far less than a thousandth of a spacing.
      EXPECT_NEAR(sample.level[q], level, 1e-3 * dx);
    }
  }
}

// Probes set on the solver are read in every step, of the state at the step's start; and a step with
// probes gives the same particles as one without.
TEST(Probes, StepsReadTheStateAtTheirStart) {
  Settled a, b;
  LoadSettled(&a);
  LoadSettled(&b);
  if (HasFatalFailure()) return;
  const ProbeSet set = TankProbes();
  ASSERT_TRUE(a.solver->SetProbes(set).ok());
  ProbeSample now;
  ASSERT_TRUE(b.solver->SampleProbes(set, &now).ok());
  const double t0 = a.solver->Time();
  ASSERT_TRUE(a.solver->Step().ok());
  ASSERT_TRUE(b.solver->Step().ok());
  const ProbeSample& read = a.solver->LastProbes();
  EXPECT_DOUBLE_EQ(read.time, t0);
  EXPECT_EQ(read.steps, now.steps);
  ASSERT_EQ(read.pressure.size(), now.pressure.size());
  for (size_t k = 0; k < now.pressure.size(); ++k) {
    // The same state, another order of summation (the step's grid against a fresh one): rounding.
    if (std::isnan(now.pressure[k])) {
      EXPECT_TRUE(std::isnan(read.pressure[k])) << set.pressure[k].name;
    } else {
      EXPECT_NEAR(read.pressure[k], now.pressure[k], 1e-4f * now.pressure[k] + 1e-3f) << set.pressure[k].name;
    }
  }
  HostFluid ha, hb;
  a.solver->Download(&ha);
  b.solver->Download(&hb);
  ASSERT_EQ(ha.size(), hb.size());
  for (size_t i = 0; i < ha.size(); ++i) {
    ASSERT_EQ(ha.id[i], hb.id[i]);
    ASSERT_EQ(ha.position[i].x, hb.position[i].x);
    ASSERT_EQ(ha.position[i].y, hb.position[i].y);
    ASSERT_EQ(ha.position[i].z, hb.position[i].z);
    ASSERT_EQ(ha.pressure[i], hb.pressure[i]);
  }
}

// Under DFSPH the probes read the state before the drift, which then runs as its own stage: the same
// numbers as the drift inside the finish stage.
TEST(Probes, DfsphStepsAreTheSameWithProbes) {
  SceneSetup scene = ::sphxr::test::SmallDamBreak();
  scene.method = SolverMethod::kDfsph;
  auto a = ::sphxr::test::CreateOrFail(scene), b = ::sphxr::test::CreateOrFail(scene);
  ASSERT_TRUE(a && b);
  ProbeSet set;
  set.pressure.push_back({"wall", {0.0f, 0.05f, 0.03f}, {-1.0f, 0.0f, 0.0f}, {}});
  set.level.push_back({"gauge", 0.05f, 0.03f, {}, {}});
  ASSERT_TRUE(a->SetProbes(set).ok());
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(a->Step().ok() && b->Step().ok());
  HostFluid ha, hb;
  a->Download(&ha);
  b->Download(&hb);
  ASSERT_EQ(ha.size(), hb.size());
  for (size_t i = 0; i < ha.size(); ++i) {
    ASSERT_EQ(ha.position[i].x, hb.position[i].x);
    ASSERT_EQ(ha.position[i].y, hb.position[i].y);
    ASSERT_EQ(ha.velocity[i].x, hb.velocity[i].x);
    ASSERT_EQ(ha.acceleration[i].w, hb.acceleration[i].w);
    ASSERT_EQ(ha.pressure[i], hb.pressure[i]);
  }
  EXPECT_GT(a->LastProbes().pressure[0], 0.0f);
}

TEST(Probes, BadProbesAreNamed) {
  std::unique_ptr<Solver> solver = ::sphxr::test::CreateOrFail(::sphxr::test::SmallDamBreak());
  ProbeSet outside;
  outside.pressure.push_back({"P9", {0.5f, 0.1f, 0.1f}, {}, {}});
  Status st = solver->SetProbes(outside);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("P9"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("outside the tank"), std::string::npos) << st.message();
  ProbeSet body;
  body.force.push_back({"F1", 0});
  st = solver->SetProbes(body);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("F1"), std::string::npos) << st.message();
  ProbeSet line;
  line.level.push_back({"G1", 0.1f, 0.3f, {}, {}});
  st = solver->SetProbes(line);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("G1"), std::string::npos) << st.message();
  EXPECT_TRUE(solver->Probes().Empty()) << "a refused set leaves the one before";
}

// The kernel fraction of a point in a box against a brute-force sum of the kernel over a fine lattice
// (a midpoint rule of 200^3 cells over the support's cube, good to ~1e-4 here): one face (where the
// exact 1D fraction is used), an edge, a corner, an obstacle's top, its side, the corner it makes with
// the floor and its top's edge (where the water wraps round it: more than half); the flat face against the
// exact fraction where the box rule is used (one face beside an obstacle far off in its cube).
TEST(Probes, KernelFractionInRegionIsTheKernelsShareOfTheWater) {
  const float H = 0.02f;
  const Aabb tank{{0.0f, 0.0f, 0.0f}, {0.2f, 0.3f, 0.1f}};
  const std::vector<Aabb> none, block{{{0.05f, 0.0f, 0.0f}, {0.1f, 0.05f, 0.1f}}};
  auto brute = [&](Vec3 p, const std::vector<Aabb>& obstacles) {
    const CubicSpline k = CubicSpline::Make(H);
    constexpr int n = 200;
    const double h = 2.0 * H / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int l = 0; l < n; ++l) {
          const Vec3 x{float(p.x - H + (i + 0.5) * h), float(p.y - H + (j + 0.5) * h), float(p.z - H + (l + 0.5) * h)};
          bool in = x.x > tank.min.x && x.x < tank.max.x && x.y > tank.min.y && x.y < tank.max.y && x.z > tank.min.z &&
                    x.z < tank.max.z;
          for (const Aabb& o : obstacles) {
            in = in && !(x.x > o.min.x && x.x < o.max.x && x.y > o.min.y && x.y < o.max.y && x.z > o.min.z && x.z < o.max.z);
          }
          if (in) sum += k.W(Length(x - p));
        }
    return sum * h * h * h;
  };
  const float dx = 0.01f;
  struct Case {
    const char* name;
    Vec3 p;
    const std::vector<Aabb>* obstacles;
  };
  const Case cases[] = {{"inside", {0.1f, 0.15f, 0.05f}, &none},       {"face", {0.1f, 0.15f, 0.5f * dx}, &none},
                        {"edge", {0.5f * dx, 0.15f, 0.5f * dx}, &none}, {"corner", {0.5f * dx, 0.5f * dx, 0.5f * dx}, &none},
                        {"box top", {0.075f, 0.05f + 0.5f * dx, 0.05f}, &block},
                        {"beside the box", {0.1f + 0.5f * dx, 0.03f, 0.05f}, &block},
                        {"box and floor", {0.1f + 0.5f * dx, 0.5f * dx, 0.05f}, &block},
                        {"box top's edge", {0.1f - 0.5f * dx, 0.05f + 0.5f * dx, 0.05f}, &block}};
  for (const Case& c : cases) {
    const double want = brute(c.p, *c.obstacles);
    EXPECT_NEAR(KernelFractionInRegion(c.p, tank, *c.obstacles, H), want, 2e-3) << c.name;
  }
  // The box rule against the exact flat-wall fraction (an obstacle in the cube but not in the support).
  const std::vector<Aabb> far{{{0.0f, 0.0f, 0.0f}, {0.081f, 0.081f, 0.1f}}};
  const Vec3 p{0.1f, 0.1f, 0.05f - 0.5f * dx + 0.05f};  // half a spacing from the z+ face
  EXPECT_NEAR(KernelFractionInRegion(p, tank, far, H), KernelFractionInside(0.5f * dx, H), 2e-4);
  // An edge and a corner hold less of the kernel than a face: the dry thresholds follow.
  const float face = KernelFractionInRegion({0.1f, 0.15f, 0.5f * dx}, tank, none, H);
  const float edge = KernelFractionInRegion({0.5f * dx, 0.15f, 0.5f * dx}, tank, none, H);
  const float corner = KernelFractionInRegion({0.5f * dx, 0.5f * dx, 0.5f * dx}, tank, none, H);
  EXPECT_GT(face, edge);
  EXPECT_GT(edge, corner);
}

// Issue 46: a sensor in a corner of flooded still water is never dry while the water is there. Its
// kernel holds less water than a sensor's in open water (KernelFractionInRegion: 0.66 in an edge, 0.53
// in a corner, half a spacing from the faces), so its threshold is lower than a flat wall's (0.33 and
// 0.27 against 0.41). Settled still water fills it enough for either threshold; the dam break below is
// where the flat-wall one failed. The readings are the Shepard averages of the particles' pressures
// (StageAgreesWithBruteForceSums holds them to brute-force sums, these sensors included).
TEST(Probes, AFloodedCornerSensorIsNeverDry) {
  Settled s;
  LoadSettled(&s);
  if (HasFatalFailure()) return;
  const float dx = s.scene.setup.params.spacing;
  const ProbeSet set = CornerSensors(dx, s.surface);
  ProbeSample sample;
  ASSERT_TRUE(s.solver->SampleProbes(set, &sample).ok());
  for (size_t k = 0; k < set.pressure.size(); ++k) {
    const Vec3 x = PointOf(set.pressure[k], dx);
    EXPECT_FALSE(std::isnan(sample.pressure[k])) << set.pressure[k].name << " at " << x.x << ", " << x.y << ", " << x.z
                                                 << " reads dry in flooded water";
    EXPECT_GT(sample.pressure[k], 0.0f) << set.pressure[k].name << " at " << x.x << ", " << x.y << ", " << x.z;
  }
  // Above the water an edge sensor is dry, as a flat wall's is.
  const float r2 = 1.0f / std::sqrt(2.0f);
  ProbeSet air;
  air.pressure.push_back({"edge_air", {0.0f, s.surface + 2.5f * dx, 0.0f}, {-r2, 0.0f, -r2}, std::sqrt(2.0f) * 0.5f * dx});
  ASSERT_TRUE(s.solver->SampleProbes(air, &sample).ok());
  EXPECT_TRUE(std::isnan(sample.pressure[0])) << "an edge sensor above the water reads " << sample.pressure[0];
}

// A flooded floor corner in a dam break: the surge runs along the floor into the far wall, and a sensor in
// the floor's corner there (half a spacing from the three faces) must read whenever the sensor above
// it in the same edge, 12 mm over the floor, reads and the corner holds water: three quarters of the
// kernel sum a flooded corner has (its rest lattice's, computed here), where its dry threshold is about
// half of it. With the flat-wall threshold it read dry at a third of the steps at which the sensor above
// it read (205 of 554, with the former fitted floor). With the free-slip floor the water draws back from
// the corner after the run-up (t = 0.354-0.366 s) while spray keeps the edge sensor above reading: the
// corner then holds 0-2 particles within two spacings, and reads dry, rightly.
TEST(Probes, TheFloorCornerSensorReadsWheneverTheSensorAboveItReads) {
  app::SceneFile file;
  ASSERT_TRUE(app::LoadScene(SPHXR_SCENES_DIR "/dam_break.json", &file).ok());
  SceneSetup scene = file.setup;
  scene.params.spacing = 0.005f;
  scene.params.diffuse = 0.0f;  // the water is the same bits without its spray (DiffuseTest), at less cost
  std::unique_ptr<Solver> solver;
  ASSERT_TRUE(Solver::Create(scene, ::sphxr::test::TestConfig(), &solver).ok());
  const float x = scene.tank.max.x, z = scene.tank.min.z, h = 0.5f * scene.params.spacing;
  const float r2 = 1.0f / std::sqrt(2.0f), r3 = 1.0f / std::sqrt(3.0f);
  ProbeSet set;
  set.pressure.push_back({"corner", {x, 0.0f, z}, {r3, -r3, -r3}, std::sqrt(3.0f) * h});
  set.pressure.push_back({"edge_12mm", {x, 0.012f, z}, {r2, 0.0f, -r2}, std::sqrt(2.0f) * h});
  ASSERT_TRUE(solver->SetProbes(set).ok());
  // The water a flooded corner holds in the sensor's kernel: sum W over the rest-lattice sites
  // (i + 1/2) dx from the three faces. The corner's dry threshold is about half of it (0.27 of the
  // whole kernel against the 0.53 of it that lies in the corner's water: KernelFractionInRegion); the
  // corner counts as watered when it holds three quarters of a flooded corner's sum.
  const float dx = scene.params.spacing;
  const CubicSpline kernel = CubicSpline::Make(scene.params.supportFactor * dx);
  double flooded = 0.0;
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      for (int k = 0; k < 8; ++k) {
        const float a = (i + 0.5f) * dx, b = (j + 0.5f) * dx, c = (k + 0.5f) * dx;
        flooded += kernel.W(std::sqrt(a * a + b * b + c * c));
      }
    }
  }
  ASSERT_GT(flooded, 0.0);
  int aboveWet = 0, cornerWet = 0, cornerDryBelowWet = 0, cornerWatered = 0;
  HostFluid fluid;
  while (solver->Time() < 0.4) {
    ASSERT_TRUE(solver->Step().ok());
    const ProbeSample& p = solver->LastProbes();
    const bool corner = !std::isnan(p.pressure[0]), above = !std::isnan(p.pressure[1]);
    aboveWet += above;
    cornerWet += corner;
    if (!above) continue;
    solver->Download(&fluid);
    double sum = 0.0;
    for (const Vec4& q : fluid.position) {
      const float a = q.x - x, b = q.y, c = q.z - z;
      sum += kernel.W(std::sqrt(a * a + b * b + c * c));
    }
    if (sum < 0.75 * flooded) continue;  // the corner holds too little water to be called flooded
    ++cornerWatered;
    if (!corner) ++cornerDryBelowWet;
  }
  RecordProperty("steps_compared", std::to_string(cornerWatered));
  ASSERT_GT(cornerWatered, 50) << "the corner must be watered while the edge above reads for the test to mean anything";
  ASSERT_GT(aboveWet, 50) << "the surge must reach the far wall's edge for the test to mean anything";
  EXPECT_EQ(cornerDryBelowWet, 0) << "the corner sensor read dry at " << cornerDryBelowWet << " of the " << aboveWet
                                  << " steps at which the sensor above it read (corner wet " << cornerWet << ")";
}

// The target: each flooded corner sensor reads rho0 g depth within 10 %. Disabled: the sensors
// read the particles, and in the settled state (summation density, wall_density walls) the particles
// along the tank's vertical edges carry 0.70 of rho0 g depth in the lowest 5 cm (0.93-0.95 above; the
// walls' and the interior's particles 0.98-1.03): the corner sensor reads 1,313 Pa where rho0 g depth is
// 1,892 Pa. Runs of 1 s from the lattice (--probes, the same sensors): DFSPH +9 .. +16 % (its flat-wall
// sensors +9 % too), PBF +14 .. +26 %, WCSPH -32 .. -8 %. The deficit is the Akinci boundary's
// flat-wall volume correction in an edge, where two wall sheets meet: a boundary model's matter.
TEST(Probes, DISABLED_AFloodedCornerSensorReadsRho0GDepthWithinTenPercent) {
  Settled s;
  LoadSettled(&s);
  if (HasFatalFailure()) return;
  const SceneSetup& setup = s.scene.setup;
  const float dx = setup.params.spacing, rho0 = setup.params.restDensity, g = -setup.gravity.y;
  const ProbeSet set = CornerSensors(dx, s.surface);
  ProbeSample sample;
  ASSERT_TRUE(s.solver->SampleProbes(set, &sample).ok());
  for (size_t k = 0; k < set.pressure.size(); ++k) {
    const Vec3 x = PointOf(set.pressure[k], dx);
    const float depth = s.surface - x.y;
    EXPECT_NEAR(sample.pressure[k], rho0 * g * depth, 0.1f * rho0 * g * depth)
        << set.pressure[k].name << " at " << x.x << ", " << x.y << ", " << x.z << " (depth " << depth << ")";
  }
}

// The dry threshold's kernel fraction: half the kernel at a wall's face, all of it a support away, and
// the integral of the kernel over all space is 1 (so the fraction at offset H is 1 by the integral).
TEST(Probes, KernelFractionInside) {
  const float H = 0.02f;
  EXPECT_NEAR(KernelFractionInside(0.0f, H), 0.5f, 1e-6f);
  EXPECT_NEAR(KernelFractionInside(H, H), 1.0f, 1e-6f);
  EXPECT_NEAR(KernelFractionInside(0.999f * H, H), 1.0f, 1e-5f);
  float last = 0.5f;
  for (float o = 0.05f * H; o < H; o += 0.05f * H) {
    const float f = KernelFractionInside(o, H);
    EXPECT_GT(f, last);
    last = f;
  }
}

}  // namespace
}  // namespace sphxr::sim
