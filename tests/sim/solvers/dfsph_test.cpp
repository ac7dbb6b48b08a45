// DFSPH (sim/src/solvers/dfsph/dfsph.h, Bender & Koschier 2017): each solve does what it claims, checked
// against sums computed here by brute force over every particle pair; the iteration cap warns instead of
// failing; the step follows the flow. (What every solver does, still water, a splash, a paddle, walls,
// restores, thread counts and cpu-reference: conformance_test.cpp; bit-identical reruns on every backend:
// tests/backend; hydrostatics, walls and Martin & Moyce at full size: tests/validation; the 5 m/s
// paddle: tests/interaction.)
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "kernel.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr {
namespace {

using sim::SceneSetup;
using sim::Vec3;
using sim::Vec4;

/// A closed box of water with no gravity and no viscosity: only the solves change the velocities.
SceneSetup QuietBox() {
  SceneSetup s = test::TankScene({0, 0, 0}, {0.12f, 0.12f, 0.12f}, 0.01f);
  s.method = sim::SolverMethod::kDfsph;
  s.openTop = false;
  s.gravity = Vec3{0.0f, 0.0f, 0.0f};
  s.params.viscosity = 0.0f;
  s.params.boundaryViscosity = 0.0f;
  s.params.fixedDt = 1e-3f;
  s.params.cfl = 1.0f;
  s.fluid.push_back(test::Block({0.0f, 0.0f, 0.0f}, {0.12f, 0.12f, 0.12f}));
  return s;
}

/// D rho^_i / Dt by brute force over every fluid and boundary particle at `x` with velocities `v` (the
/// solver's own kernel and volumes: V = spacing^3 for the fluid, Psi_b / rho0 for the walls).
struct BruteForce {
  const SceneSetup& scene;
  const std::vector<Vec4>& boundary;  // w = Psi_b
  sim::CubicSpline k = sim::CubicSpline::Make(scene.params.spacing * scene.params.supportFactor);
  float volume = scene.params.spacing * scene.params.spacing * scene.params.spacing;

  /// The rate and the number of fluid and boundary neighbours of particle i.
  double Rate(const std::vector<Vec4>& x, const std::vector<Vec4>& v, size_t i, int* neighbours) const {
    double rate = 0.0;
    *neighbours = 0;
    const Vec3 xi = Xyz(x[i]), vi = Xyz(v[i]);
    for (size_t j = 0; j < x.size(); ++j) {
      const Vec3 d = xi - Xyz(x[j]);
      const float r = Length(d);
      if (j == i || r >= k.H) continue;
      ++*neighbours;
      rate += volume * Dot(vi - Xyz(v[j]), d * k.GradFactor(r));
    }
    for (const Vec4& b : boundary) {
      const Vec3 d = xi - Xyz(b);
      const float r = Length(d);
      if (r >= k.H) continue;
      ++*neighbours;
      rate += b.w / scene.params.restDensity * Dot(vi, d * k.GradFactor(r));
    }
    return rate;
  }
};

TEST(Dfsph, DivergenceSolveRemovesTheDivergenceOfARandomField) {
  SceneSetup scene = QuietBox();
  scene.params.maxIterations = 0;  // no density solve: the step is the divergence solve and a drift
  scene.params.minIterations = 0;
  scene.params.densityTolerance = 10.0f;
  scene.params.maxDivergenceIterations = 1000;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  sim::HostFluid fluid = test::DownloadFluid(*solver);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (Vec4& v : fluid.velocity) v = Vec4{u(rng), u(rng), u(rng), 0.0f};
  ASSERT_TRUE(solver->Upload(fluid).ok());
  sim::HostBoundary boundary;
  solver->DownloadBoundary(&boundary);
  const BruteForce brute{scene, boundary.position};
  const float dt = scene.params.fixedDt;

  auto meanPositiveRate = [&](const std::vector<Vec4>& x, const std::vector<Vec4>& v) {
    double sum = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      int neighbours = 0;
      const double rate = brute.Rate(x, v, i, &neighbours);
      if (neighbours >= 20) sum += std::max(rate, 0.0);  // the solve leaves sheet and spray particles alone
    }
    return sum / static_cast<double>(x.size());
  };
  const double before = meanPositiveRate(fluid.position, fluid.velocity) * dt;
  ASSERT_TRUE(solver->Step().ok());
  const sim::StepInfo& info = solver->LastStep();
  // The velocities after the solve, at the positions the solve saw (the drift moved them by dt v).
  sim::HostFluid after = test::DownloadFluid(*solver);
  for (size_t i = 0; i < after.size(); ++i) {
    for (int a = 0; a < 3; ++a) (&after.position[i].x)[a] -= dt * (&after.velocity[i].x)[a];
  }
  const double residual = meanPositiveRate(after.position, after.velocity) * dt;
  const double tolerance = 0.01 * scene.params.divergenceTolerance;
  EXPECT_GT(before, 10.0 * tolerance) << "the random field must need the solve";
  EXPECT_GT(info.solve.divergenceIterations, 0);
  EXPECT_LT(info.solve.divergenceIterations, 1000);
  EXPECT_LE(info.solve.divergenceError, tolerance);
  // The brute-force sums see the same field: the solver's error, up to the drift's rounding (positions
  // recovered as x - dt v differ from the solve's by a few float ulps of a 0.1 m coordinate).
  EXPECT_LE(residual, tolerance * 1.01 + 1e-6) << "before the solve " << before;
}

TEST(Dfsph, DensitySolveBringsACompressedBlockToTheTolerance) {
  SceneSetup scene = QuietBox();
  scene.params.maxDivergenceIterations = 0;
  scene.params.maxIterations = 200;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  sim::HostFluid fluid = test::DownloadFluid(*solver);
  // Squeeze the block by 4 % toward its centre: about 12 % above rest density inside.
  for (Vec4& x : fluid.position) {
    for (float* c : {&x.x, &x.y, &x.z}) *c = 0.06f + 0.96f * (*c - 0.06f);
  }
  ASSERT_TRUE(solver->Upload(fluid).ok());
  ASSERT_TRUE(solver->Step().ok());
  const sim::StepInfo& info = solver->LastStep();
  const float tolerance = 0.01f * scene.params.densityTolerance;
  EXPECT_GT(info.meanDensityError, 0.05f) << "the block must start compressed";
  EXPECT_GE(info.solve.densityIterations, 1);
  EXPECT_LT(info.solve.densityIterations, scene.params.maxIterations);
  EXPECT_LE(info.solve.densityError, tolerance);
}

TEST(Dfsph, ReachingTheIterationCapWarnsWithTheErrorAndGoesOn) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.method = sim::SolverMethod::kDfsph;
  scene.params.maxIterations = 1;
  scene.params.minIterations = 1;
  scene.params.densityTolerance = 1e-5f;
  test::LogCapture log;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_TRUE(test::StepN(*solver, 100));
  EXPECT_GT(solver->GetTotals().iterationCapSteps, 0);
  EXPECT_EQ(log.Count("reached max_iterations", LogLevel::kWarn), 1) << "once per simulated second";
  EXPECT_EQ(test::FirstNonFinite(test::DownloadFluid(*solver)), "");
}

TEST(Dfsph, StepFollowsTheFlowSpeedNotTheSoundSpeed) {
  SceneSetup wcsph = test::SmallDamBreak(0.01f);
  wcsph.params.maxDt = 0.01f;
  SceneSetup dfsph = wcsph;
  dfsph.method = sim::SolverMethod::kDfsph;
  auto a = test::CreateOrFail(wcsph);
  auto b = test::CreateOrFail(dfsph);
  ASSERT_TRUE(a && b);
  // At rest DFSPH takes max_dt (or the viscosity bound); WCSPH the acoustic CFL step, cfl h / c.
  const float h = wcsph.params.spacing * wcsph.params.supportFactor * 0.5f;
  EXPECT_NEAR(a->StableDt(), wcsph.params.cfl * h / a->SoundSpeed(), 1e-6f * a->StableDt());
  EXPECT_GT(b->StableDt(), 5.0f * a->StableDt());
  ASSERT_TRUE(test::StepN(*b, 50));
  const float v = b->LastStep().maxSpeed;
  EXPECT_LE(b->StableDt(), dfsph.params.cfl * h / v * (1.0f + 1e-6f));
}

}  // namespace
}  // namespace sphxr
