// The solver's kinematic bodies (sim/include/sphxr/sim/rigid.h): a target segment is followed across the
// substeps with position linear and rotation slerp, and every boundary particle carries v + w x r.
#include <gtest/gtest.h>

#include <limits>

#include <cmath>

#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/rigid.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

/// A 0.3 x 0.2 x 0.2 m tank with 5 cm of water and a small blade on a handle at height `y`.
SceneSetup PaddleScene(float y) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.2f, 0.2f}, 0.01f);
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.05f, 0.2f}));
  RigidBodySetup body;
  body.shapes = interaction::BladeOnHandle(0.05f, 0.01f, 0.06f, 0.05f, 0.012f);
  body.points = interaction::SamplePaddle(body.shapes, scene.params.spacing);
  body.pose.position = Vec3{0.1f, y, 0.1f};
  scene.bodies.push_back(body);
  return scene;
}

// Fluid is not seeded inside a body at its start pose; how much that leaves out is said at creation.
// Independent count: the fluid of the same scene without the body.
TEST(BodyMotion, TheFluidABodyDisplacesAtItsStartIsSaid) {
  SceneSetup inWater = PaddleScene(0.03f);
  SceneSetup without = inWater;
  without.bodies.clear();
  test::LogCapture log;
  auto a = test::CreateOrFail(without);
  auto b = test::CreateOrFail(inWater);
  ASSERT_TRUE(a && b);
  const int displaced = a->FluidCount() - b->FluidCount();
  ASSERT_GT(displaced, 0);
  EXPECT_EQ(log.Count("the paddles at their start poses leave " + std::to_string(displaced) + " of the " +
                      std::to_string(a->FluidCount()) + " fluid lattice sites empty"),
            1)
      << log.All();
  test::LogCapture quiet;
  ASSERT_TRUE(test::CreateOrFail(PaddleScene(0.15f)));  // above the water: nothing to say
  EXPECT_EQ(quiet.Count("lattice sites empty"), 0) << quiet.All();
}

TEST(BodyMotion, FollowsTheSegmentWithTheRigidVelocity) {
  const SceneSetup scene = PaddleScene(0.15f);  // the paddle above the water
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->BodyCount(), 1);

  // 0.05 s: move 5 cm along x and turn 90 degrees about y.
  const double duration = 0.05;
  const Vec3 from = scene.bodies[0].pose.position, to = from + Vec3{0.05f, 0.0f, 0.0f};
  const float half = 0.25f * 3.14159265f;
  const Quat q1{std::cos(half), 0.0f, std::sin(half), 0.0f};
  ASSERT_TRUE(solver->SetBodyTarget(0, Pose{to, q1}, duration).ok());
  std::vector<Vec4> pos, vel;
  int steps = 0;
  while (solver->Time() < duration - 1e-9) {
    ASSERT_TRUE(test::StepN(*solver, 1));
    ++steps;
    const double t = solver->Time();
    const float u = static_cast<float>(std::min(1.0, t / duration));
    const Pose p = solver->BodyPose(0);
    EXPECT_NEAR(p.position.x, from.x + 0.05f * u, 2e-6f) << "t = " << t;
    // slerp from identity: a rotation by u * 90 degrees about y
    EXPECT_NEAR(p.orientation.w, std::cos(half * u), 2e-5f);
    EXPECT_NEAR(p.orientation.y, std::sin(half * u), 2e-5f);
    // During the step: v = 1 m/s along x (the last step may end past the target and hold), w = pi/2 / 0.05 s.
    if (t <= duration) {
      EXPECT_NEAR(solver->BodyVelocity(0).x, 1.0f, 1e-3f);
      EXPECT_NEAR(solver->BodyAngularVelocity(0).y, 0.5f * 3.14159265f / 0.05f, 0.05f);
    }
    // Every particle: v + w x r with r from the origin at the start of the step.
    solver->DownloadBodies(&pos, &vel);
    const Vec3 v = solver->BodyVelocity(0), w = solver->BodyAngularVelocity(0);
    const Vec3 origin = p.position - v * solver->LastStep().dt;  // the start-of-step origin
    for (size_t k = 0; k < pos.size(); k += 7) {
      const Vec3 expected = v + Cross(w, Xyz(pos[k]) - origin);
      ASSERT_NEAR(vel[k].x, expected.x, 1e-3f);
      ASSERT_NEAR(vel[k].y, expected.y, 1e-3f);
      ASSERT_NEAR(vel[k].z, expected.z, 1e-3f);
    }
  }
  EXPECT_GT(steps, 5) << "several substeps per segment";
  // Held after the target time, at rest.
  ASSERT_TRUE(test::StepN(*solver, 3));
  EXPECT_EQ(solver->BodyPose(0).position.x, to.x);
  EXPECT_EQ(Length(solver->BodyVelocity(0)), 0.0f);
  // A target time not after now relocates at once, at rest.
  ASSERT_TRUE(solver->SetBodyTarget(0, Pose{from, Quat{}}, solver->Time()).ok());
  EXPECT_EQ(solver->BodyPose(0).position.x, from.x);
  EXPECT_FALSE(solver->SetBodyTarget(1, Pose{}, 1.0).ok());
  EXPECT_FALSE(solver->SetBodyTarget(0, Pose{Vec3{NAN, 0, 0}, Quat{}}, 1.0).ok());
}

// A restart (state files): a body's whole motion read mid-segment and set on a fresh solver of the same
// scene gives the same next steps, body and water, bit for bit; bad motions and late calls are refused.
TEST(BodyMotion, ARestartContinuesTheMotionExactly) {
  const SceneSetup scene = PaddleScene(0.08f);  // the paddle in the water
  auto through = test::CreateOrFail(scene);
  ASSERT_TRUE(through);
  ASSERT_TRUE(through->SetBodyTarget(0, Pose{Vec3{0.2f, 0.08f, 0.1f}, scene.bodies[0].pose.orientation}, 0.1).ok());
  for (int k = 0; k < 15; ++k) ASSERT_TRUE(through->Step().ok());
  const BodyMotionState motion = through->BodyMotionOf(0);
  EXPECT_GT(Length(motion.velocity), 0.5f) << "saved while moving along its segment (1 m/s)";
  HostFluid fluid;
  through->Download(&fluid);
  const SolverClock clock = through->Clock();

  auto restored = test::CreateOrFail(scene);
  ASSERT_TRUE(restored);
  ASSERT_TRUE(restored->Restore(fluid, clock).ok());
  ASSERT_TRUE(restored->SetBodyMotion(0, motion).ok());
  for (int k = 0; k < 10; ++k) {
    ASSERT_TRUE(through->Step().ok());
    ASSERT_TRUE(restored->Step().ok());
    ASSERT_EQ(through->LastStep().dt, restored->LastStep().dt) << "step " << k;
  }
  const Pose a = through->BodyPose(0), b = restored->BodyPose(0);
  EXPECT_EQ(a.position.x, b.position.x);
  EXPECT_EQ(a.orientation.w, b.orientation.w);
  HostFluid fa, fb;
  through->Download(&fa);
  restored->Download(&fb);
  ASSERT_EQ(fa.size(), fb.size());
  for (size_t i = 0; i < fa.size(); ++i) {
    ASSERT_EQ(fa.position[i].x, fb.position[i].x) << "particle " << i;
    ASSERT_EQ(fa.velocity[i].y, fb.velocity[i].y) << "particle " << i;
  }

  BodyMotionState bad = motion;
  bad.toTime = std::numeric_limits<double>::quiet_NaN();
  auto fresh = test::CreateOrFail(scene);
  ASSERT_TRUE(fresh);
  Status s = fresh->SetBodyMotion(0, bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("non-finite"), std::string::npos) << s.message();
  EXPECT_FALSE(fresh->SetBodyMotion(1, motion).ok()) << "no body 1";
  bad = motion;  // a zero quaternion would place the body's particles at its origin
  bad.to.orientation = Quat{0.0f, 0.0f, 0.0f, 0.0f};
  s = fresh->SetBodyMotion(0, bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("far from unit length"), std::string::npos) << s.message();
  bad = motion;  // ends before it begins (a zero-length segment ahead made the CFL step 0)
  bad.toTime = bad.fromTime - 0.01;
  EXPECT_FALSE(fresh->SetBodyMotion(0, bad).ok());
  bad = motion;  // a little off unit length: normalised
  bad.to.orientation.w *= 1.01f;
  ASSERT_TRUE(fresh->SetBodyMotion(0, bad).ok());
  const Quat q = fresh->BodyMotionOf(0).to.orientation;
  EXPECT_NEAR(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z, 1.0f, 1e-6f);
  s = restored->SetBodyMotion(0, motion);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("before the first step"), std::string::npos) << s.message();
}

TEST(BodyMotion, BadBodiesAreRefused) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.2f, 0.2f}, 0.01f);
  RigidBodySetup body;
  body.shapes = interaction::BladeOnHandle();
  scene.bodies.push_back(body);  // no points
  std::unique_ptr<Solver> solver;
  Status s = Solver::Create(scene, test::TestConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("boundary particles"), std::string::npos) << s.message();
  scene.bodies[0].points = {Vec3{0, 0, 0}};
  scene.bodies[0].shapes[0].radius = -1.0f;
  s = Solver::Create(scene, test::TestConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("radius"), std::string::npos) << s.message();
  // A body that reaches further than the tank's diagonal (0.41 m here) is refused by name; a capsule of
  // radius 10 m used to sample 3M points and hang in the O(n^2) volume sums.
  scene.bodies[0].shapes = interaction::BladeOnHandle();
  scene.bodies[0].points = {Vec3{0, 0, 0}, Vec3{0.5f, 0, 0}};
  s = Solver::Create(scene, test::TestConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("more than the tank"), std::string::npos) << s.message();
  scene.bodies[0].points = {Vec3{0, 0, 0}, Vec3{0.3f, 0, 0}};
  EXPECT_TRUE(Solver::Create(scene, test::TestConfig(), &solver).ok());
}

}  // namespace
}  // namespace sphxr::sim
