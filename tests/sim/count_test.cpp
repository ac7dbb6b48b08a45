// Counting a scene's particles (used to refuse scenes before allocating) must give exactly what
// sampling creates: the counts are computed in closed form, the samples by walking the lattice.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "sampling.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

SceneSetup Scene(bool openTop, int layers, bool obstacles) {
  SceneSetup s;
  s.params.spacing = 0.01f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.237f, 0.3f, 0.1f}};  // 0.237 is not a multiple of the spacing
  s.openTop = openTop;
  s.boundaryLayers = layers;
  s.fluid.push_back({{{0.0f, 0.0f, 0.0f}, {0.1f, 0.15f, 0.1f}}, {}});
  s.fluid.push_back({{{0.13f, 0.05f, 0.0f}, {0.237f, 0.1f, 0.0533f}}, {}});
  if (obstacles) {
    s.obstacles.push_back({{0.05f, 0.0f, 0.02f}, {0.08f, 0.04f, 0.06f}});
    s.obstacles.push_back({{0.15f, 0.1f, 0.05f}, {0.153f, 0.2f, 0.06f}});  // thinner than a spacing
  }
  return s;
}

TEST(CountParticles, ClosedFormEqualsSampling) {
  for (bool openTop : {true, false}) {
    for (int layers = 1; layers <= 4; ++layers) {
      for (bool obstacles : {false, true}) {
        const SceneSetup s = Scene(openTop, layers, obstacles);
        std::vector<Vec4> fluid, boundary;
        std::vector<float> alpha;
        const int64_t nf = SampleFluid(s, &fluid);
        const int64_t nb = SampleBoundary(s, &boundary, &alpha);
        EXPECT_EQ(nf, static_cast<int64_t>(fluid.size()));
        EXPECT_EQ(nb, static_cast<int64_t>(boundary.size()));
        EXPECT_EQ(alpha.size(), boundary.size());
        const ParticleCounts c = CountParticles(s);
        EXPECT_EQ(c.fluid, nf) << "open top " << openTop << ", layers " << layers << ", obstacles " << obstacles;
        EXPECT_EQ(c.boundary, nb) << "open top " << openTop << ", layers " << layers << ", obstacles " << obstacles;
      }
    }
  }
}

// Scenes too large for the solver are refused by Solver::Create before anything is allocated, with a
// one-line reason. A tank of 5e9 m made the grid size overflow int (negative, so it passed the size
// check) and the counts overflow int64, and the run allocated until it died.
TEST(CountParticles, ScenesTooLargeAreRefusedBeforeAllocating) {
  SceneSetup huge;
  huge.params.spacing = 1.0f;
  huge.tank = {{0.0f, 0.0f, 0.0f}, {5e9f, 5e9f, 5e9f}};
  huge.fluid.push_back({{{0.0f, 0.0f, 0.0f}, {4.0f, 4.0f, 4.0f}}, {}});
  std::unique_ptr<Solver> solver;
  Status s = Solver::Create(huge, ::sphxr::test::AllCoresConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("neighbour grid"), std::string::npos) << s.message();

  // 820^3 = 551M fluid particles in a grid of 420 cells per axis: more than the SIMD stages' 32-bit
  // gather offsets can reach (2^29), refused by count whatever the machine's memory.
  SceneSetup many;
  many.params.spacing = 0.01f;
  many.tank = {{0.0f, 0.0f, 0.0f}, {8.2f, 8.2f, 8.2f}};
  many.fluid.push_back({{{0.0f, 0.0f, 0.0f}, {8.2f, 8.2f, 8.2f}}, {}});
  ASSERT_GE(CountParticles(many).fluid, int64_t{1} << 29);
  s = Solver::Create(many, ::sphxr::test::AllCoresConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("at most 536870911 of each"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
}

}  // namespace
}  // namespace sphxr::sim
