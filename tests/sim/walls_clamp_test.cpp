// The clamp behind the walls: where a fluid particle is put back (the tank's faces and the obstacles),
// and that each clamp is counted at its site.
#include <gtest/gtest.h>

#include "support.h"

namespace sphxr::sim {
namespace {

TEST(WallsClampTest, SiteNames) {
  EXPECT_EQ(ClampSiteName(0), "x- wall");
  EXPECT_EQ(ClampSiteName(2), "floor");
  EXPECT_EQ(ClampSiteName(5), "z+ wall");
  EXPECT_EQ(ClampSiteName(kTankFaces + 3), "obstacles[3]");
}

TEST(WallsClampTest, TooManyObstaclesAreRefusedByName) {
  SceneSetup scene = test::TankScene({0, 0, 0}, {1, 1, 1}, 0.05f);
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.3f, 0.3f}));
  for (int k = 0; k <= kMaxObstacles; ++k) {
    const float x = 0.4f + 0.03f * static_cast<float>(k);
    scene.obstacles.push_back(test::Box({x, 0.0f, 0.5f}, {x + 0.02f, 0.1f, 0.6f}));
  }
  std::unique_ptr<Solver> solver;
  const Status s = Solver::Create(scene, test::TestConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("obstacles"), std::string::npos) << s.message();
}

// A particle put inside an obstacle (the lattice never seeds one there; a fast flow can carry one in)
// is pushed out to the nearest face and counted at the obstacle; one put past the x+ face, at the x+ wall.
TEST(WallsClampTest, ObstacleInteriorAndTankFacesAreCheckedAndCounted) {
  const float dx = 0.02f;
  SceneSetup scene = test::TankScene({0, 0, 0}, {0.6f, 0.4f, 0.2f}, dx);
  scene.gravity = {0, 0, 0};
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.2f, 0.2f, 0.2f}));
  const Aabb obstacle = test::Box({0.3f, 0.0f, 0.0f}, {0.4f, 0.2f, 0.2f});
  scene.obstacles.push_back(obstacle);
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  HostFluid f = test::DownloadFluid(*solver);
  ASSERT_GT(f.size(), 2u);
  // Particle 0 into the obstacle, 3 mm inside its x- face, moving on into it; particle 1 past the tank's
  // x+ face clamp (a quarter spacing inside the face), moving out.
  f.position[0] = Vec4{0.303f, 0.1f, 0.1f, 0.0f};
  f.velocity[0] = Vec4{1.0f, 0.0f, 0.0f, 0.0f};
  f.position[1] = Vec4{0.599f, 0.3f, 0.1f, 0.0f};
  f.velocity[1] = Vec4{1.0f, 0.0f, 0.0f, 0.0f};
  const uint32_t inside = f.id[0], outside = f.id[1];
  ASSERT_TRUE(solver->Upload(f).ok());
  ASSERT_TRUE(solver->Step().ok());
  const HostFluid after = test::DownloadFluid(*solver);
  const auto at = test::IndexById(after);
  const Vec4 a = after.position[at.at(inside)];
  EXPECT_LE(a.x, obstacle.min.x - 0.25f * dx + 1e-6f) << "on the obstacle's x- face, grown by the clamp's inset";
  EXPECT_LE(after.velocity[at.at(inside)].x, 0.0f) << "no velocity into the obstacle";
  const Vec4 b = after.position[at.at(outside)];
  EXPECT_EQ(b.x, scene.tank.max.x - 0.25f * dx);
  const Totals& t = solver->GetTotals();
  EXPECT_EQ(t.clampedEvents, 2);
  EXPECT_EQ(t.clampedAt[kTankFaces + 0], 1) << "obstacles[0]";
  EXPECT_EQ(t.clampedAt[1], 1) << "x+ wall";
  EXPECT_EQ(t.particleSteps, static_cast<int64_t>(f.size()));
}

}  // namespace
}  // namespace sphxr::sim
