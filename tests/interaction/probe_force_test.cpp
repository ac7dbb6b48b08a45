// A force probe on a moving body reads the body's load of the step its pressure sensors describe: the
// fluid's pressure and viscous reaction on the body's particles (Solver::LastBodyLoad, the haptics'
// source), with the state's time and step.
#include <gtest/gtest.h>

#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/probes.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

TEST(ProbeForce, ReadsTheBodysLoadOfTheStep) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.2f, 0.2f}, 0.01f);
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.05f, 0.2f}));
  RigidBodySetup body;
  body.shapes = interaction::BladeOnHandle(0.05f, 0.01f, 0.06f, 0.05f, 0.012f);
  body.points = interaction::SamplePaddle(body.shapes, scene.params.spacing);
  body.pose.position = Vec3{0.1f, 0.03f, 0.1f};
  scene.bodies.push_back(body);
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ProbeSet set;
  set.force.push_back({"blade", 0});
  set.pressure.push_back({"floor", {0.15f, 0.0f, 0.1f}, {0.0f, -1.0f, 0.0f}, {}});
  ASSERT_TRUE(solver->SetProbes(set).ok());
  // The body moves through the water, so its load is not zero.
  ASSERT_TRUE(solver->SetBodyTarget(0, Pose{{0.2f, 0.03f, 0.1f}, Quat{}}, 0.05).ok());
  for (int i = 0; i < 10; ++i) {
    const double before = solver->Time();
    ASSERT_TRUE(solver->Step().ok());
    const ProbeSample& read = solver->LastProbes();
    EXPECT_EQ(read.time, before);
    ASSERT_EQ(read.load.size(), 1u);
    const BodyLoad& load = solver->LastBodyLoad(0);
    EXPECT_EQ(read.load[0].force.x, load.force.x);
    EXPECT_EQ(read.load[0].force.y, load.force.y);
    EXPECT_EQ(read.load[0].force.z, load.force.z);
    EXPECT_EQ(read.load[0].torque.x, load.torque.x);
    EXPECT_EQ(read.load[0].torque.y, load.torque.y);
    EXPECT_EQ(read.load[0].torque.z, load.torque.z);
  }
  EXPECT_GT(Length(solver->LastProbes().load[0].force), 0.0f);
}

}  // namespace
}  // namespace sphxr::sim
