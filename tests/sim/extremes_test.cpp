// Inputs at the edges: a fixed time step far above the stability limit, degenerate particle sets,
// validate mode on injected non-finite values, and a CUDA request on a machine without a GPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "support.h"

namespace sphxr::sim {
namespace {

/// Runs `steps` steps checking, after each, that nothing is non-finite and no particle was lost.
void RunChecked(Solver& solver, int steps, const std::string& what) {
  const int n = solver.FluidCount();
  for (int s = 1; s <= steps; ++s) {
    const Status st = solver.Step();
    ASSERT_TRUE(st.ok()) << what << ", step " << s << ": " << st.message();
    ASSERT_TRUE(std::isfinite(solver.LastStep().dt) && solver.LastStep().dt > 0.0f)
        << what << ", step " << s << ": dt = " << solver.LastStep().dt;
    ASSERT_TRUE(std::isfinite(solver.LastStep().maxSpeed)) << what << ", step " << s;
    if (s % 10 == 0 || s == steps) {
      const HostFluid f = test::DownloadFluid(solver);
      ASSERT_EQ(static_cast<int>(f.size()), n) << what << ", step " << s;
      ASSERT_EQ(test::FirstNonFinite(f), "") << what << ", step " << s;
    }
  }
  EXPECT_EQ(solver.GetTotals().steps, steps) << what;
}

// ---- (a) fixed_dt above the CFL limit --------------------------------------------------------------

TEST(ExtremesTest, FixedDtAboveTheStabilityLimitIsClampedAndWarnedOnce) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.params.fixedDt = 0.05f;
  const SolverParams& p = scene.params;
  // Independent bound: the acoustic CFL condition with the sound speed of the Tait equation.
  const float h = 0.5f * p.spacing * p.supportFactor;
  const float c = std::sqrt(p.exponent * p.stiffness / p.restDensity);
  const float cflBound = std::min(p.maxDt, p.cfl * h / c);
  ASSERT_LT(cflBound, 0.05f / 10);

  test::LogCapture log;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const int steps = 200;
  for (int s = 1; s <= steps; ++s) {
    ASSERT_TRUE(solver->Step().ok());
    const float dt = solver->LastStep().dt;
    ASSERT_GT(dt, 0.0f) << "step " << s;
    ASSERT_LE(dt, cflBound * (1.0f + 1e-6f)) << "step " << s << ": dt " << dt << " above the CFL bound " << cflBound;
  }
  const HostFluid f = test::DownloadFluid(*solver);
  EXPECT_EQ(test::FirstNonFinite(f), "");
  EXPECT_EQ(f.size(), 900u);
  EXPECT_EQ(solver->GetTotals().dtClampedSteps, steps) << "every step's fixed dt is above the limit";
  EXPECT_GT(solver->Time(), 0.0);
  EXPECT_LT(solver->Time(), steps * cflBound * 1.0001);
  EXPECT_EQ(log.Count("fixed_dt", LogLevel::kWarn), 1) << "the clamp must be warned about exactly once; log:\n"
                                                       << log.All();
}

TEST(ExtremesTest, FixedDtBelowTheLimitIsUsedExactly) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.params.fixedDt = 1e-5f;
  test::LogCapture log;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  for (int s = 1; s <= 50; ++s) {
    ASSERT_TRUE(solver->Step().ok());
    ASSERT_EQ(solver->LastStep().dt, 1e-5f) << "step " << s;
  }
  EXPECT_EQ(solver->GetTotals().dtClampedSteps, 0);
  EXPECT_NEAR(solver->Time(), 50 * 1e-5, 1e-9);
  EXPECT_EQ(log.Count("fixed_dt"), 0) << log.All();
}

// ---- (b) degenerate scenes -------------------------------------------------------------------------

SceneSetup SmallTank() {
  SceneSetup s = test::TankScene({0, 0, 0}, {0.1f, 0.1f, 0.1f}, 0.01f);
  s.params.maxDt = 1e-3f;
  return s;
}

TEST(ExtremesTest, NoFluidParticles) {
  SceneSetup scene = SmallTank();
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  EXPECT_EQ(solver->FluidCount(), 0);
  EXPECT_GT(solver->BoundaryCount(), 0);
  RunChecked(*solver, 100, "no fluid");
  EXPECT_EQ(solver->LastStep().maxSpeed, 0.0f);
  EXPECT_EQ(solver->LastStep().clamped, 0);
}

TEST(ExtremesTest, OneParticleFallsAndComesToRestAboveTheFloor) {
  SceneSetup scene = SmallTank();
  scene.fluid.push_back(test::Block({0.04f, 0.05f, 0.04f}, {0.05f, 0.06f, 0.05f}));
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->FluidCount(), 1);
  RunChecked(*solver, 100, "one particle");
  // Free fall first: after 100 steps it is still in the air and has fallen as g t^2 / 2 (symplectic Euler
  // lands within one step of that).
  HostFluid f = test::DownloadFluid(*solver);
  const double t = solver->Time();
  const double fallen = 0.055 - f.position[0].y;
  ASSERT_LT(0.5 * 9.81 * t * t, 0.04) << "the test assumes the particle is still falling";
  EXPECT_NEAR(fallen, 0.5 * 9.81 * t * t, 9.81 * t * solver->LastStep().dt * 1.5) << "t = " << t;
  EXPECT_NEAR(f.velocity[0].y, -9.81 * t, 1e-3 * 9.81 * t);
  EXPECT_NEAR(f.position[0].x, 0.045f, 1e-6f);
  EXPECT_NEAR(f.position[0].z, 0.045f, 1e-6f);

  // Then it lands and comes to rest on the floor, above the tank floor. A lone particle's own density is
  // only rho0 / pi, and the floor's boundary particles add at most gamma rho0 (about 0.7 rho0, reached on
  // the boundary sheet itself), so the clamped-at-zero pressure cannot hold it: it sinks to the domain
  // edge a quarter spacing above the floor, where the clamp stops it. That is where it must rest.
  float lowest = 1.0f;
  while (solver->Time() < 1.5) {
    ASSERT_TRUE(solver->Step().ok());
    f = test::DownloadFluid(*solver);
    ASSERT_EQ(test::FirstNonFinite(f), "") << "t = " << solver->Time();
    lowest = std::min(lowest, f.position[0].y);
  }
  const float dx = scene.params.spacing;
  const float y = f.position[0].y;
  const float speed = std::sqrt(f.velocity[0].x * f.velocity[0].x + f.velocity[0].y * f.velocity[0].y +
                                f.velocity[0].z * f.velocity[0].z);
  EXPECT_LT(speed, 1e-3f) << "still moving at t = " << solver->Time() << " s, y = " << y;
  EXPECT_GE(y, scene.tank.min.y + 0.25f * dx) << "below the domain edge";
  EXPECT_LT(y, scene.tank.min.y + 1.5f * dx) << "did not come down to the floor";
  EXPECT_GE(lowest, scene.tank.min.y + 0.25f * dx) << "went below the domain edge";
  EXPECT_NEAR(f.position[0].x, 0.045f, 1e-4f) << "drifted sideways";
  EXPECT_NEAR(f.position[0].z, 0.045f, 1e-4f) << "drifted sideways";
  RecordProperty("rest_height_in_spacings", std::to_string(y / dx));
  RecordProperty("clamped_events", std::to_string(solver->GetTotals().clampedEvents));
}

TEST(ExtremesTest, TwoCoincidentParticles) {
  SceneSetup scene = SmallTank();
  scene.fluid.push_back(test::Block({0.04f, 0.05f, 0.04f}, {0.06f, 0.06f, 0.05f}));
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->FluidCount(), 2);
  HostFluid f = test::DownloadFluid(*solver);
  f.position[1] = f.position[0];
  ASSERT_TRUE(solver->Upload(f).ok());
  RunChecked(*solver, 100, "two coincident particles");
}

TEST(ExtremesTest, WholeBlockInsideOneCell) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.2f, 0.2f, 0.2f}, 0.01f);
  scene.params.maxDt = 1e-3f;
  // 2 x 2 x 2 at the rest spacing, aligned with one cell of the grid (cells are 2 dx wide).
  {
    auto probe = test::CreateOrFail(scene);
    ASSERT_TRUE(probe);
    const Solver::GridInfo g = probe->Grid();
    const int cx = 9, cy = 9, cz = 9;
    const Vec3 lo{g.origin.x + cx * g.cellSize, g.origin.y + cy * g.cellSize, g.origin.z + cz * g.cellSize};
    const Vec3 hi{lo.x + g.cellSize, lo.y + g.cellSize, lo.z + g.cellSize};
    SceneSetup one = scene;
    one.fluid.push_back(test::Block(lo, hi));
    auto solver = test::CreateOrFail(one);
    ASSERT_TRUE(solver);
    ASSERT_EQ(solver->FluidCount(), 8);
    const HostFluid f = test::DownloadFluid(*solver);
    for (const Vec4& p : f.position) {
      ASSERT_EQ(static_cast<int>((p.x - g.origin.x) / g.cellSize), cx);
      ASSERT_EQ(static_cast<int>((p.y - g.origin.y) / g.cellSize), cy);
      ASSERT_EQ(static_cast<int>((p.z - g.origin.z) / g.cellSize), cz);
    }
    RunChecked(*solver, 100, "2x2x2 block in one cell");
  }
  // 4 x 4 x 4 squeezed into one cell (spacing 0.45 dx: 11 times the rest density), placed by Upload.
  {
    SceneSetup squeezed = scene;
    squeezed.fluid.push_back(test::Block({0.08f, 0.08f, 0.08f}, {0.12f, 0.12f, 0.12f}));
    auto solver = test::CreateOrFail(squeezed);
    ASSERT_TRUE(solver);
    ASSERT_EQ(solver->FluidCount(), 64);
    const Solver::GridInfo g = solver->Grid();
    HostFluid f = test::DownloadFluid(*solver);
    const float dx = scene.params.spacing;
    const Vec3 lo{g.origin.x + 9 * g.cellSize + 0.1f * dx, g.origin.y + 9 * g.cellSize + 0.1f * dx,
                  g.origin.z + 9 * g.cellSize + 0.1f * dx};
    for (size_t i = 0; i < f.size(); ++i) {
      const int a = static_cast<int>(i % 4), b = static_cast<int>((i / 4) % 4), c = static_cast<int>(i / 16);
      f.position[i] = MakeVec4(Vec3{lo.x + 0.45f * dx * a, lo.y + 0.45f * dx * b, lo.z + 0.45f * dx * c});
    }
    ASSERT_TRUE(solver->Upload(f).ok());
    RunChecked(*solver, 100, "4x4x4 block squeezed into one cell");
  }
}

TEST(ExtremesTest, BlockTouchingTheWalls) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.2f, 0.2f, 0.1f}, 0.01f);
  scene.params.maxDt = 1e-3f;
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.2f, 0.1f, 0.1f}));  // the four walls and the floor
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->FluidCount(), 20 * 10 * 10);
  RunChecked(*solver, 100, "block touching the walls");
  // and nothing left the tank
  const HostFluid f = test::DownloadFluid(*solver);
  for (const Vec4& p : f.position) {
    ASSERT_TRUE(p.x >= 0.0f && p.x <= 0.2f && p.y >= 0.0f && p.y <= 0.2f && p.z >= 0.0f && p.z <= 0.1f)
        << "particle outside the tank at [" << p.x << ", " << p.y << ", " << p.z << "]";
  }
}

// ---- (c) validate mode -------------------------------------------------------------------------------

/// A validated solver after one step (so the particles are sorted and index != id for some), with a
/// non-finite value injected into `field` of a particle whose id differs from its index. Returns its id.
uint32_t InjectNaN(Solver& solver, const char* field) {
  EXPECT_TRUE(solver.Step().ok()) << "a healthy step must pass validation";
  HostFluid f = test::DownloadFluid(solver);
  size_t k = 0;
  while (k < f.size() && f.id[k] == k) ++k;
  EXPECT_LT(k, f.size()) << "the sort did not permute anything";
  k = std::min(k + 7, f.size() - 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (std::string(field) == "velocity") f.velocity[k].y = nan;
  else f.position[k].x = nan;
  EXPECT_TRUE(solver.Upload(f).ok());
  return f.id[k];
}

TEST(ExtremesTest, ValidateNamesParticleAndFieldOfANaNVelocity) {
  SolverConfig config = test::TestConfig();
  config.validate = true;
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f), config);
  ASSERT_TRUE(solver);
  const uint32_t id = InjectNaN(*solver, "velocity");
  const Status s = solver->Step();
  ASSERT_FALSE(s.ok()) << "validate mode must stop on a NaN velocity";
  EXPECT_NE(s.message().find("particle " + std::to_string(id)), std::string::npos)
      << "message must name particle id " << id << ": " << s.message();
  EXPECT_NE(s.message().find("velocity"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("step 2"), std::string::npos) << s.message();
}

TEST(ExtremesTest, ValidateNamesParticleAndFieldOfANaNPosition) {
  SolverConfig config = test::TestConfig();
  config.validate = true;
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f), config);
  ASSERT_TRUE(solver);
  const uint32_t id = InjectNaN(*solver, "position");
  const Status s = solver->Step();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("particle " + std::to_string(id)), std::string::npos)
      << "message must name particle id " << id << ": " << s.message();
  EXPECT_NE(s.message().find("position"), std::string::npos) << s.message();
}

TEST(ExtremesTest, ValidateNamesTheStageWhereAValueOverflows) {
  // 2500 coincident particles: density 2500 m W(0) = 2500/pi rho0, and with gamma = 10, B = 1e10 Pa the Tait
  // pressure B (rho/rho0)^10 overflows float. Every input is finite; the density stage makes the inf.
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.2f, 0.2f}, 0.01f);
  scene.params.exponent = 10.0f;
  scene.params.stiffness = 1e10f;
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.25f, 0.1f, 0.1f}));
  SolverConfig config = test::TestConfig();
  config.validate = true;
  auto solver = test::CreateOrFail(scene, config);
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->FluidCount(), 2500);
  HostFluid f = test::DownloadFluid(*solver);
  for (Vec4& p : f.position) p = MakeVec4(Vec3{0.15f, 0.1f, 0.1f});
  ASSERT_TRUE(solver->Upload(f).ok());
  const Status s = solver->Step();
  ASSERT_FALSE(s.ok()) << "the overflowing pressure must be caught";
  EXPECT_NE(s.message().find("pressure"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("'density'"), std::string::npos) << "must name the stage: " << s.message();
  // the named particle really has a non-finite pressure
  const size_t at = s.message().find("particle ");
  ASSERT_NE(at, std::string::npos) << s.message();
  const uint32_t id = static_cast<uint32_t>(std::strtoul(s.message().c_str() + at + 9, nullptr, 10));
  f = test::DownloadFluid(*solver);
  const auto byId = test::IndexById(f);
  ASSERT_TRUE(byId.count(id)) << "no particle with id " << id << ": " << s.message();
  EXPECT_FALSE(std::isfinite(f.pressure[byId.at(id)])) << "particle " << id << " pressure " << f.pressure[byId.at(id)];
}

// Without validate mode a NaN is caught too: the step's reduction counts non-finite particles (its
// maxima drop NaN, so before, a NaN particle sat in the grid's last cell, exported and saved as NaN).
TEST(ExtremesTest, WithoutValidateANaNParticleStopsTheStep) {
  for (const char* field : {"velocity", "position"}) {
    auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f));
    ASSERT_TRUE(solver);
    InjectNaN(*solver, field);  // after one good step
    const double before = solver->Time();
    const Status s = solver->Step();
    ASSERT_FALSE(s.ok()) << field << ": the step must fail";
    EXPECT_NE(s.message().find("1 fluid particles became non-finite"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("--validate"), std::string::npos) << s.message();
    EXPECT_EQ(solver->Time(), before) << "a failed step leaves the clock";
  }
}

// A step too small to move the clock would loop forever in a run to a given time; Step says so instead.
// Here a particle shot off at 3e19 m/s: finite, so not a non-finite particle, but its squared speed
// overflows float and the CFL step is 0. (At 1e36 m/s its neighbours' viscous terms overflow, and the
// step's non-finite count stops the run first.)
TEST(ExtremesTest, ATimeStepThatCannotAdvanceTheClockIsAnError) {
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f));
  ASSERT_TRUE(solver);
  ASSERT_TRUE(solver->Step().ok());
  HostFluid f = test::DownloadFluid(*solver);
  f.velocity[0] = MakeVec4(Vec3{3e19f, 0.0f, 0.0f});
  ASSERT_TRUE(solver->Upload(f).ok());
  Status s = Status::Ok();
  for (int k = 0; k < 5 && s.ok(); ++k) s = solver->Step();
  ASSERT_FALSE(s.ok()) << "the run must stop, not spin";
  EXPECT_NE(s.message().find("the time step collapsed"), std::string::npos) << s.message();
  EXPECT_GT(solver->Time(), 0.0);
}

TEST(ExtremesTest, ValidateModePassesAHealthyRun) {
  SolverConfig config = test::TestConfig();
  config.validate = true;
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.01f), config);
  ASSERT_TRUE(solver);
  RunChecked(*solver, 30, "validated dam break");
}

// ---- (d) devices ---------------------------------------------------------------------------------------

TEST(ExtremesTest, CudaWithoutAGpuIsAClearError) {
  if (CudaDeviceCount() > 0) GTEST_SKIP() << CudaDeviceCount() << " CUDA device(s) present";
  SolverConfig config = test::TestConfig();
  config.device = Device::kCuda;
  std::unique_ptr<Solver> solver;
  const Status s = Solver::Create(test::SmallDamBreak(0.01f), config, &solver);
  ASSERT_FALSE(s.ok()) << "--device cuda must be refused without a GPU";
  EXPECT_EQ(solver, nullptr);
  EXPECT_NE(s.message().find("--device cuda"), std::string::npos) << s.message();
  const bool says = s.message().find("no CUDA device") != std::string::npos ||
                    s.message().find("without the CUDA backend") != std::string::npos;
  EXPECT_TRUE(says) << "the message should say why: " << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line: " << s.message();
}

TEST(ExtremesTest, DeviceAutoPicksWhatIsThere) {
  SolverConfig config = test::TestConfig();
  config.device = Device::kAuto;
  std::unique_ptr<Solver> solver;
  const Status s = Solver::Create(test::SmallDamBreak(0.01f), config, &solver);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(solver->ActiveDevice(), CudaDeviceCount() > 0 ? Device::kCuda : Device::kCpu);
  ASSERT_TRUE(test::StepN(*solver, 3));
}

TEST(ExtremesTest, NegativeThreadsRefused) {
  SolverConfig config = test::TestConfig();
  config.threads = -1;
  std::unique_ptr<Solver> solver;
  const Status s = Solver::Create(test::SmallDamBreak(0.01f), config, &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("threads"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace sphxr::sim
