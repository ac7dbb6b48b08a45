// The behaviours every backend must have, over every backend on the machine (test::AvailableDevices:
// cpu, cpu-reference, and cuda where a GPU answers): bit-identical reruns and restores within a backend,
// every reuse preset, both wall models, a moving body, and the surface, the last three also compared
// with the `cpu` backend within stated tolerances (the backends round differently, so not bit for bit).
// The whole sim and interaction suites also run on cpu-reference (SPHXR_TEST_DEVICE, tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "backend.h"
#include "sphxr/interaction/paddle.h"
#include "support.h"

namespace sphxr::sim {
namespace {

class Behaviour : public ::testing::TestWithParam<Device> {
 protected:
  SolverConfig Config(int threads = 1) const {
    SolverConfig c;
    c.device = GetParam();
    c.threads = threads;
    return c;
  }
};

/// Every field of every particle the same, bit for bit (in the same sorted order).
::testing::AssertionResult BitIdentical(const HostFluid& a, const HostFluid& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << a.size() << " against " << b.size() << " particles";
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::memcmp(&a.position[i], &b.position[i], sizeof(Vec4)) || std::memcmp(&a.velocity[i], &b.velocity[i], sizeof(Vec4)) ||
        std::memcmp(&a.density[i], &b.density[i], sizeof(float)) || a.idle[i] != b.idle[i] || a.id[i] != b.id[i]) {
      return ::testing::AssertionFailure() << "particle " << i << " (id " << a.id[i] << ") differs";
    }
  }
  return ::testing::AssertionSuccess();
}

SceneSetup SmallDeepTank() {
  // deep_tank.json's shape at 4 cm: a 20 x 18 x 18 pool and a 5^3 drop.
  SceneSetup s = test::TankScene({0, 0, 0}, {0.8f, 1.0f, 0.72f}, 0.04f);
  s.params.stiffness = 100000.0f;
  s.params.viscosity = s.params.boundaryViscosity = 0.05f;
  s.params.fixedDt = 0.0006f;
  FluidBlock pool = test::Block({0, 0, 0}, {0.8f, 0.72f, 0.72f});
  pool.hydrostatic = true;
  s.fluid = {pool, test::Block({0.06f, 0.78f, 0.06f}, {0.26f, 0.98f, 0.26f})};
  return s;
}

/// tank_rest.json at 2 cm (tests/sim/test_scenes.h has the same): 10 x 10 x 5 particles in the box.
SceneSetup SmallRestTank(SceneSetup::WallPressure walls) {
  SceneSetup s;
  s.params.spacing = 0.02f;
  s.params.stiffness = 57000.0f;
  s.params.viscosity = s.params.boundaryViscosity = 0.3f;
  s.params.maxDt = 0.001f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.2f, 0.3f, 0.1f}};
  s.fluid.push_back(FluidBlock{{{0.0f, 0.0f, 0.0f}, {0.2f, 0.2f, 0.1f}}, {}});
  s.wallPressure = walls;
  return s;
}

TEST_P(Behaviour, RerunsAndThreadCountsAreBitIdentical) {
  const SceneSetup scene = test::SmallDamBreak(0.01f);
  HostFluid runs[3];
  for (int k = 0; k < 3; ++k) {
    auto solver = test::CreateOrFail(scene, Config(k == 2 ? 2 : 1));
    ASSERT_TRUE(solver);
    ASSERT_TRUE(test::StepN(*solver, 150));
    solver->Download(&runs[k]);
  }
  EXPECT_TRUE(BitIdentical(runs[0], runs[1])) << "two runs on one thread";
  if (GetParam() != Device::kCuda) {
    EXPECT_TRUE(BitIdentical(runs[0], runs[2])) << "one thread against two";
  }
}

TEST_P(Behaviour, ARestoreContinuesTheRunBitForBit) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  ASSERT_TRUE(ApplyReusePreset("balanced", &scene.reuse));  // the idle counts travel with the state
  auto through = test::CreateOrFail(scene, Config());
  ASSERT_TRUE(through && test::StepN(*through, 60));
  HostFluid saved;
  through->Download(&saved);
  const SolverClock clock = through->Clock();
  ASSERT_TRUE(test::StepN(*through, 60));
  auto restored = test::CreateOrFail(scene, Config());
  ASSERT_TRUE(restored);
  ASSERT_TRUE(restored->Restore(saved, clock).ok());
  ASSERT_TRUE(test::StepN(*restored, 60));
  EXPECT_TRUE(BitIdentical(test::DownloadFluid(*through), test::DownloadFluid(*restored)));
}

TEST_P(Behaviour, DfsphRerunsThreadCountsAndRestoresAreBitIdentical) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.method = sim::SolverMethod::kDfsph;
  HostFluid runs[3];
  for (int k = 0; k < 3; ++k) {
    auto solver = test::CreateOrFail(scene, Config(k == 2 ? 2 : 1));
    ASSERT_TRUE(solver);
    ASSERT_TRUE(test::StepN(*solver, 80));
    EXPECT_GT(solver->GetTotals().densityIterations, 0);
    solver->Download(&runs[k]);
  }
  EXPECT_TRUE(BitIdentical(runs[0], runs[1])) << "two runs on one thread";
  if (GetParam() != Device::kCuda) {
    EXPECT_TRUE(BitIdentical(runs[0], runs[2])) << "one thread against two (the solves' stopping sums are integers)";
  }
  auto first = test::CreateOrFail(scene, Config());
  ASSERT_TRUE(first && test::StepN(*first, 40));
  auto restored = test::CreateOrFail(scene, Config());
  ASSERT_TRUE(restored);
  ASSERT_TRUE(restored->Restore(test::DownloadFluid(*first), first->Clock()).ok());
  ASSERT_TRUE(test::StepN(*restored, 40));
  EXPECT_TRUE(BitIdentical(runs[0], test::DownloadFluid(*restored))) << "40 + 40 steps through a restore";
}

TEST_P(Behaviour, EveryReusePresetSkipsWorkAndStaysCalm) {
  for (const char* preset : {"accurate", "balanced", "fast"}) {
    SCOPED_TRACE(preset);
    SceneSetup scene = SmallDeepTank();
    ASSERT_TRUE(ApplyReusePreset(preset, &scene.reuse));
    auto solver = test::CreateOrFail(scene, Config());
    ASSERT_TRUE(solver);
    double active = 0.0;
    const int steps = 240;
    for (int k = 0; k < steps; ++k) {
      ASSERT_TRUE(test::StepN(*solver, 1));
      active += solver->LastStep().activeFraction;
    }
    const HostFluid f = test::DownloadFluid(*solver);
    EXPECT_EQ(test::FirstNonFinite(f), "");
    EXPECT_LT(active / steps, 0.95) << "reuse skipped (almost) nothing";
    // The pool starts at hydrostatic rest and the drop falls for 0.1 s: the pool stays calm.
    EXPECT_LT(solver->LastStep().maxSpeed, 2.0f);
  }
}

TEST_P(Behaviour, ReuseWithIdleZeroIsBitIdenticalToReuseOff) {
  SceneSetup off = test::SmallDamBreak(0.01f);
  SceneSetup zero = off;
  ASSERT_TRUE(ApplyReusePreset("balanced", &zero.reuse));
  zero.reuse.idle = 0;
  HostFluid a, b;
  for (auto* s : {&off, &zero}) {
    auto solver = test::CreateOrFail(*s, Config());
    ASSERT_TRUE(solver && test::StepN(*solver, 100));
    solver->Download(s == &off ? &a : &b);
  }
  EXPECT_TRUE(BitIdentical(a, b));
}

// Both wall models hold water at rest in a closed box (tank_rest at 2 cm), and agree with `cpu`'s run:
// 300 steps from the same lattice part by rounding only while the water is calm (the lattice's first
// settling is gentle), so the positions agree to a small fraction of a spacing.
TEST_P(Behaviour, BothWallModelsHoldTheWaterAndAgreeWithCpu) {
  for (auto walls : {SceneSetup::WallPressure::kMirrored, SceneSetup::WallPressure::kWallDensity}) {
    SCOPED_TRACE(walls == SceneSetup::WallPressure::kMirrored ? "mirrored" : "wall_density");
    const SceneSetup scene = SmallRestTank(walls);
    HostFluid result[2];
    for (int k = 0; k < 2; ++k) {
      SolverConfig c = Config();
      if (k == 1) c.device = Device::kCpu;
      auto solver = test::CreateOrFail(scene, c);
      ASSERT_TRUE(solver && test::StepN(*solver, 300));
      EXPECT_EQ(solver->GetTotals().clampedEvents, 0) << "the walls let water through to the domain clamp";
      EXPECT_LT(solver->LastStep().maxSpeed, 0.3f);
      solver->Download(&result[k]);
    }
    const auto byId = test::IndexById(result[1]);
    float worst = 0.0f;
    for (size_t i = 0; i < result[0].size(); ++i) {
      const Vec4 a = result[0].position[i], b = result[1].position[byId.at(result[0].id[i])];
      worst = std::max(worst, std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)));
    }
    EXPECT_LT(worst, 0.01f * scene.params.spacing) << "positions after 300 steps against cpu";
  }
}

TEST_P(Behaviour, AMovingBodyFeelsTheWaterAndPushesItAside) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.2f, 0.2f, 0.1f}, 0.01f);
  scene.params.maxDt = 1e-3f;
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.2f, 0.1f, 0.1f}));
  RigidBodySetup body;
  body.shapes = interaction::BladeOnHandle(0.05f, 0.01f, 0.06f, 0.05f, 0.012f);
  body.points = interaction::SamplePaddle(body.shapes, scene.params.spacing);
  body.pose.position = Vec3{0.05f, 0.06f, 0.05f};
  scene.bodies.push_back(body);
  auto solver = test::CreateOrFail(scene, Config());
  ASSERT_TRUE(solver);
  Pose target = solver->BodyPose(0);
  target.position.x = 0.15f;
  ASSERT_TRUE(solver->SetBodyTarget(0, target, 0.1).ok());
  while (solver->Time() < 0.1) ASSERT_TRUE(test::StepN(*solver, 1));
  EXPECT_NEAR(solver->BodyPose(0).position.x, 0.15f, 1e-4f);
  EXPECT_LT(solver->LastBodyLoad(0).force.x, 0.0f) << "drag against the motion";
  const HostFluid f = test::DownloadFluid(*solver);
  EXPECT_EQ(test::FirstNonFinite(f), "");
  int inside = 0;
  for (size_t i = 0; i < f.size(); ++i) inside += solver->BodyDistance(0, Xyz(f.position[i])) < 0.0f ? 1 : 0;
  EXPECT_EQ(inside, 0) << "fluid particles inside the body after its push-out";
}

TEST_P(Behaviour, TheSurfaceOfTheSameParticlesMatchesCpu) {
  const SceneSetup scene = test::SmallDamBreak(0.01f);
  SolverConfig cpuConfig = Config();
  cpuConfig.device = Device::kCpu;
  auto tested = test::CreateOrFail(scene, Config());
  auto cpu = test::CreateOrFail(scene, cpuConfig);
  ASSERT_TRUE(tested && cpu);
  ASSERT_TRUE(test::StepN(*cpu, 80));
  ASSERT_TRUE(tested->Upload(test::DownloadFluid(*cpu)).ok());
  SurfaceParams params;
  params.cellSize = 0.0093f;
  SurfaceMesh meshTested, meshCpu;
  SurfaceStats statsTested, statsCpu;
  ASSERT_TRUE(tested->ExtractSurface(params, &meshTested, &statsTested).ok());
  ASSERT_TRUE(cpu->ExtractSurface(params, &meshCpu, &statsCpu).ok());
  EXPECT_GT(statsCpu.triangles, 100);
  // The field sums the same kernel terms in the same order (only fused multiply-adds may differ):
  // within 1e-5 of its iso level of 0.5. A sample within that of the level may flip a case.
  SurfaceGrid gridTested, gridCpu;
  std::vector<float> fieldTested, fieldCpu;
  tested->BackendForTests()->Surface()->DownloadField(&gridTested, &fieldTested);
  cpu->BackendForTests()->Surface()->DownloadField(&gridCpu, &fieldCpu);
  // The CPU's lattice covers the particles' bounding box, the others' the clamp box, on the same lines:
  // each sample against the other's at the same point, the clamp box's other samples beyond every kernel.
  const test::SurfaceFieldDiff d = test::CompareSurfaceFields(gridTested, fieldTested, gridCpu, fieldCpu);
  ASSERT_TRUE(d.nested);
  EXPECT_LT(d.worst, 1e-5f);
  EXPECT_EQ(d.outside, 0.0f);
  EXPECT_NEAR(static_cast<double>(statsTested.vertices), static_cast<double>(statsCpu.vertices), 0.01 * statsCpu.vertices);
}

INSTANTIATE_TEST_SUITE_P(Backends, Behaviour, ::testing::ValuesIn(test::AvailableDevices()),
                         [](const ::testing::TestParamInfo<Device>& info) { return test::DeviceTestName(info.param); });

}  // namespace
}  // namespace sphxr::sim
