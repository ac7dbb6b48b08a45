// A fluid block with "hydrostatic": true starts compressed to the Tait density of its depth, so a deep
// pool begins at rest instead of falling into its own compression and ringing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "sampling.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

// The deep_tank pool's column: 36 spacings of 2 cm, B = 1e5 Pa (1 % compression at the floor).
SceneSetup Column() {
  SceneSetup s;
  s.params.spacing = 0.02f;
  s.params.stiffness = 100000.0f;
  s.params.viscosity = 0.05f;
  s.params.boundaryViscosity = 0.05f;
  s.params.fixedDt = 0.0003f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.16f, 0.9f, 0.16f}};
  FluidBlock pool{{{0.0f, 0.0f, 0.0f}, {0.16f, 0.72f, 0.16f}}, {}};
  pool.hydrostatic = true;
  s.fluid.push_back(pool);
  return s;
}

// Each layer holds the mass rho0 dx per area of the uncompressed lattice. Independently of the sampler's
// closed form: the pressure at a layer boundary is the weight of the water above it (p = g rho0 times the
// uncompressed height above), the Tait density there rho = rho0 (1 + p/B)^(1/gamma), and the layer spacing
// is dx rho0 / rho at the midpoint between two layers (midpoint rule). The lowest layer stands half a
// spacing above the floor, where the uncompressed lattice has it: the column rests on the floor.
// Also at exponent 1 (allowed), where the sampler's closed form takes its limit (it was 0/0: every
// particle NaN), with B gamma kept (the same sound speed, so about the same compression).
TEST(HydrostaticStart, LayersFollowTheTaitColumnAndStandOnTheFloor) {
  for (const float gamma : {SceneSetup{}.params.exponent, 1.0f}) {
  SCOPED_TRACE("exponent " + std::to_string(gamma));
  SceneSetup s = Column();
  s.params.stiffness *= s.params.exponent / gamma;
  s.params.exponent = gamma;
  std::vector<Vec4> fluid;
  SampleFluid(s, &fluid);
  std::map<int, double> layerY;  // uncompressed layer index -> height (every particle of a layer alike)
  const double dx = s.params.spacing;
  for (const Vec4& p : fluid) layerY.emplace(static_cast<int>(std::lround(p.y / dx - 0.5)), p.y);
  ASSERT_EQ(layerY.size(), 36u);
  EXPECT_NEAR(layerY.begin()->second, 0.5 * dx, 1e-6) << "the column must stand on the floor, not hang from its top";
  const double top = 36 * dx, g = 9.81, rho0 = s.params.restDensity, B = s.params.stiffness;
  double compressedSum = 0.0;
  for (int j = 0; j + 1 < 36; ++j) {
    const double depthAboveMid = top - (j + 1) * dx;  // uncompressed water above the midpoint of j, j+1
    const double rho = rho0 * std::pow(1.0 + rho0 * g * depthAboveMid / B, 1.0 / s.params.exponent);
    const double expected = dx * rho0 / rho;
    // 1e-5 dx: float positions near 0.7 m round by ~6e-8 m; a layer's compression is up to 1e-2 dx.
    EXPECT_NEAR(layerY[j + 1] - layerY[j], expected, 1e-5 * dx) << "layers " << j << ", " << j + 1;
    compressedSum += dx - expected;
  }
  // The whole column is shorter by the sum of the layers' compression (about 3.4 mm here): the surface
  // comes down, the floor stays.
  EXPECT_NEAR(layerY.rbegin()->second, top - 0.5 * dx - compressedSum, 1e-5);
  EXPECT_GT(compressedSum, 0.003);
  }
}

// Started hydrostatic, the column stays put: after 30 steps (9 ms) the lowest layer's mean vertical
// speed is small. Before the sampler anchored the column on the floor, the whole column's compression
// (3.4 mm) was a gap under the water and the lowest layer fell at 0.3 m/s by step 20.
TEST(HydrostaticStart, DeepColumnDoesNotFall) {
  std::unique_ptr<Solver> solver;
  const Status st = Solver::Create(Column(), ::sphxr::test::AllCoresConfig(), &solver);
  ASSERT_TRUE(st.ok()) << st.message();
  for (int i = 0; i < 30; ++i) ASSERT_TRUE(solver->Step().ok());
  HostFluid h;
  solver->Download(&h);
  double vy = 0.0;
  int n = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    if (h.position[i].y < 0.02f) {
      vy += h.velocity[i].y;
      ++n;
    }
  }
  ASSERT_GT(n, 0);
  EXPECT_LT(std::fabs(vy / n), 0.03) << "mean vertical speed of the lowest layer, m/s";
}

}  // namespace
}  // namespace sphxr::sim
