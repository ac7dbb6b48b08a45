#pragma once
// Scenes shared by the sim tests.
#include "sphxr/sim/params.h"

namespace sphxr::sim::test {

/// tank_rest.json at twice the spacing: 10 x 10 x 5 particles of water in a closed box, the wall model
/// and the artificial viscosity (fluid and walls) as given.
inline SceneSetup SmallRestTank(SceneSetup::WallPressure walls, float alpha) {
  SceneSetup s;
  s.params.spacing = 0.02f;
  s.params.stiffness = 57000.0f;
  s.params.viscosity = alpha;
  s.params.boundaryViscosity = alpha;
  s.params.maxDt = 0.001f;
  s.tank = {{0.0f, 0.0f, 0.0f}, {0.2f, 0.3f, 0.1f}};
  s.fluid.push_back(FluidBlock{{{0.0f, 0.0f, 0.0f}, {0.2f, 0.2f, 0.1f}}, {}});
  s.wallPressure = walls;
  return s;
}

}  // namespace sphxr::sim::test
