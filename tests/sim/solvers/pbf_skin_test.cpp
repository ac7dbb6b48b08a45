// PBF's neighbour lists with a skin (pbf_skin, solvers/pbf/pbf.h): kept over a frame's substeps they give
// the frame that lists built every substep give, to float rounding; a paddle faster than the skin allows
// rebuilds them and leaves no particle inside it; the same bits at every thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "sim/same_bits.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr {
namespace {

using sim::HostFluid;
using sim::SceneSetup;
using sim::Vec3;
using sim::Vec4;

/// A closed 8-spacing box with a 6 x 6 x 6 block, jittered by up to 0.1 spacing and moving at up to
/// 0.17 m/s (0.1 along each axis): over a frame's first two substeps (7.4 ms) a particle moves 1.3 mm,
/// gravity adds 0.3 mm and the corrections that undo the jitter at most its 1.7 mm, within half the
/// skin (5 mm at pbf_skin 1), so a frame keeps its lists.
std::unique_ptr<sim::Solver> MovingBox(float skin) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.08f, 0.08f, 0.08f}, 0.01f);
  scene.method = sim::SolverMethod::kPbf;
  scene.openTop = false;
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.06f, 0.06f, 0.06f}));
  scene.params.pbfSkin = skin;
  auto solver = test::CreateOrFail(scene);
  if (!solver) return solver;
  HostFluid fluid = test::DownloadFluid(*solver);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t i = 0; i < fluid.size(); ++i) {
    fluid.position[i].x += 0.1f * scene.params.spacing * u(rng);
    fluid.position[i].y += 0.1f * scene.params.spacing * u(rng);
    fluid.position[i].z += 0.1f * scene.params.spacing * u(rng);
    fluid.velocity[i] = Vec4{0.1f * u(rng), 0.1f * u(rng), 0.1f * u(rng), 0.0f};
  }
  EXPECT_TRUE(solver->Upload(fluid).ok());
  return solver;
}

/// The sort stage's total time: on the CPU backend it changes exactly on the steps that sort (a step
/// that keeps its grid never laps the stage). The plain launcher (cpu-reference, CUDA) launches the
/// gated sort every step, the flag deciding on the device: nil there.
double SortSeconds(const sim::Solver& solver) {
  return solver.GetTotals().stageSeconds[static_cast<int>(sim::Stage::kSort)];
}
bool SkipsTheSortOnTheHost(const sim::Solver& solver) { return solver.ActiveDevice() == sim::Device::kCpu; }

// A frame of 3 substeps on lists built at its first (pbf_skin 0.5) against the same frame with the
// density stage's lists every substep (pbf_skin 0): the same pairs within the support at every x*, so
// only the sums' order differs. Each run is within 1e-4 of a spacing a step of MM13's Algorithm 1 in
// double (pbf_test.cpp, from float's 2^-24 over sums of ~30 terms), and a step carries the last one's
// difference on: the two runs are within twice that, summed over the frame's steps.
TEST(PbfSkin, AFrameOnKeptListsAgreesWithListsEverySubstepToRounding) {
  auto kept = MovingBox(1.0f), every = MovingBox(0.0f);
  ASSERT_TRUE(kept && every);
  const int substeps = 3;
  double sorted = 0.0;
  for (int step = 0; step < substeps; ++step) {
    ASSERT_TRUE(kept->Step().ok());
    ASSERT_TRUE(every->Step().ok());
    if (step == 0) sorted = SortSeconds(*kept);
    if (!SkipsTheSortOnTheHost(*kept)) continue;
    EXPECT_GT(sorted, 0.0);
    EXPECT_EQ(SortSeconds(*kept), sorted) << "substep " << step + 1 << " kept the frame's grid and lists";
  }
  const HostFluid a = test::DownloadFluid(*kept), b = test::DownloadFluid(*every);
  const auto byId = test::IndexById(b);
  const double spacing = 0.01, dt = kept->LastStep().dt, posTol = 2.0 * substeps * 1e-4 * spacing;
  double worstX = 0.0, worstV = 0.0, moved = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const size_t j = byId.at(a.id[i]);
    auto distance = [](Vec4 p, Vec4 q) { return std::hypot(double{p.x} - q.x, double{p.y} - q.y, double{p.z} - q.z); };
    worstX = std::max(worstX, distance(a.position[i], b.position[j]));
    worstV = std::max(worstV, distance(a.velocity[i], b.velocity[j]));
    moved = std::max(moved, static_cast<double>(std::fabs(a.velocity[i].y)));
  }
  EXPECT_LT(worstX, posTol);
  EXPECT_LT(worstV, posTol / dt);
  EXPECT_GT(moved, 0.02) << "the frame must move the particles for the comparison to mean anything";
}

// A blade pushed through a pool at 2 m/s: 7.4 mm a 1/270 s substep, past half the skin (2.5 mm at
// pbf_skin 0.5 and a 1 cm spacing), so the lists are rebuilt within frames, not only at their first
// substep; and the push-out leaves no particle inside the blade.
TEST(PbfSkin, APaddleFasterThanTheSkinRebuildsTheListsAndLeavesNoParticleInside) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.2f, 0.1f}, 0.01f);
  scene.method = sim::SolverMethod::kPbf;
  scene.params.pbfSkin = 0.5f;
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.1f, 0.1f}));
  const float blade = 0.06f, thickness = 0.012f;
  sim::RigidBodySetup body;
  body.shapes = interaction::BladeOnHandle(0.06f, 0.01f, thickness, blade, blade);  // x thin, y deep, z wide
  body.points = interaction::SamplePaddle(body.shapes, scene.params.spacing);
  body.pose.position = Vec3{0.05f, 0.14f, 0.05f};  // the blade from y = 0.02 to 0.08 m, z = 0.02 to 0.08 m
  scene.bodies.push_back(body);
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const double travel = 0.2, duration = 0.1;
  sim::Pose target = solver->BodyPose(0);
  target.position.x += static_cast<float>(travel);
  ASSERT_TRUE(solver->SetBodyTarget(0, target, duration).ok());
  const int substeps = static_cast<int>(scene.params.pbfSubsteps);
  int step = 0, midFrameSorts = 0;
  while (solver->Time() < duration - 1e-9) {
    const double before = SortSeconds(*solver);
    ASSERT_TRUE(solver->Step().ok());
    ++step;
    if ((step - 1) % substeps != 0 && SortSeconds(*solver) != before) ++midFrameSorts;
  }
  if (SkipsTheSortOnTheHost(*solver)) EXPECT_GT(midFrameSorts, 0) << "a substep inside a frame rebuilt the lists";
  const HostFluid f = test::DownloadFluid(*solver);
  ASSERT_EQ(test::FirstNonFinite(f), "");
  const Vec3 at = solver->BodyPose(0).position;
  int inside = 0;
  for (const Vec4& x : f.position) {
    inside += std::fabs(x.x - at.x) < 0.5f * thickness && x.y > 0.02f && x.y < 0.08f &&
              std::fabs(x.z - at.z) < 0.5f * blade;
  }
  EXPECT_EQ(inside, 0) << "fluid particles inside the blade at its end pose";
}

// The small dam break under PBF on kept lists, 30 steps (ten frames): the same bits on 1 and 2 threads.
TEST(PbfSkin, SameBitsAtEveryThreadCount) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.method = sim::SolverMethod::kPbf;
  scene.params.pbfSkin = 0.5f;
  const auto one = sim::same_bits::RunScene(scene, 1, 30);
  const auto two = sim::same_bits::RunScene(scene, 2, 30);
  sim::same_bits::ExpectIdentical(one, two);
}

}  // namespace
}  // namespace sphxr
