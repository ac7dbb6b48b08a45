// Stability at the extremes: the dam break (scenes/dam_break.json, run at twice its spacing as the base
// so that the whole sweep stays affordable) for 1 simulated second with stiffness x0.1 and x100,
// viscosity 0 and x100, spacing x0.5 and x2 of that base. No NaN, particle count conserved, maximum
// speed bounded by kSpeedBound * sqrt(2 g H) with H the column height; settings that will not give usable
// water are named at start-up.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr {
namespace {

// Multiples of sqrt(2 g H), the free-fall speed from the column top. Measured (1 s each): base 2.2,
// stiffness x0.1 1.4, x100 4.85 (a few particles shot out where the jet hits the far wall at c = 150 m/s),
// viscosity 0 2.5, x100 0.58, spacing x0.5 2.45, x2 1.7; with walls of their own density (the walls'
// pressure from the fluid beside them, docs/design/walls.md) base 1.34, viscosity 0 1.45.
constexpr float kSpeedBound = 5.0f;

struct Extreme {
  const char* name;
  float stiffnessScale = 1.0f;
  float viscosityScale = 1.0f;
  float spacingScale = 1.0f;      // of the base (twice the scene's spacing)
  const char* startupWarning = nullptr;  // expected in the log at start-up, if the setting is unusable
  bool wallDensity = false;       // tank.wall_pressure = "wall_density" instead of the scene's mirrored walls
};

// ctest and gtest name the case by its setting instead of by the bytes of the struct.
void PrintTo(const Extreme& e, std::ostream* os) { *os << e.name; }

class Stability : public ::testing::TestWithParam<Extreme> {};

TEST_P(Stability, OneSecondOfDamBreak) {
  const Extreme& e = GetParam();
  app::SceneFile scene;
  ASSERT_TRUE(app::LoadScene(SPHXR_SCENES_DIR "/dam_break.json", &scene).ok());
  scene.setup.params.diffuse = 0.0f;  // the water is the same bits without its spray (DiffuseTest), at less cost
  sim::SolverParams& p = scene.setup.params;
  p.spacing *= 2.0f * e.spacingScale;
  p.stiffness *= e.stiffnessScale;
  p.viscosity *= e.viscosityScale;
  if (e.wallDensity) scene.setup.wallPressure = sim::SceneSetup::WallPressure::kWallDensity;
  const float columnHeight = 2.0f * scene.damBreak->columnWidth;
  const float vRef = std::sqrt(2.0f * 9.81f * columnHeight);

  std::vector<std::string> warnings;
  SetLogSink([&](LogLevel level, const std::string& text) {
    if (level >= LogLevel::kWarn) warnings.push_back(text);
  });
  std::unique_ptr<sim::Solver> solver;
  const Status created = sim::Solver::Create(scene.setup, sim::SolverConfig{}, &solver);
  SetLogSink(nullptr);
  ASSERT_TRUE(created.ok()) << created.message();
  if (e.startupWarning) {
    bool found = false;
    for (const std::string& w : warnings) found = found || w.find(e.startupWarning) != std::string::npos;
    EXPECT_TRUE(found) << "expected a start-up warning containing '" << e.startupWarning << "'";
  }

  const int n = solver->FluidCount();
  ASSERT_GT(n, 0);
  float maxSpeed = 0.0f;
  while (solver->Time() < 1.0) {
    ASSERT_TRUE(solver->Step().ok());
    const float v = solver->LastStep().maxSpeed;
    ASSERT_TRUE(std::isfinite(v)) << "non-finite at t = " << solver->Time();
    maxSpeed = std::max(maxSpeed, v);
  }
  sim::HostFluid host;
  solver->Download(&host);
  EXPECT_EQ(static_cast<int>(host.size()), n);
  for (size_t i = 0; i < host.size(); ++i) {
    ASSERT_TRUE(std::isfinite(host.position[i].x) && std::isfinite(host.position[i].y) &&
                std::isfinite(host.position[i].z))
        << "particle " << host.id[i];
  }
  RecordProperty("max_speed_over_vref", std::to_string(maxSpeed / vRef));
  RecordProperty("steps", std::to_string(solver->GetTotals().steps));
  EXPECT_LE(maxSpeed, kSpeedBound * vRef) << "max speed " << maxSpeed << " m/s, sqrt(2gH) = " << vRef << " m/s";
}

INSTANTIATE_TEST_SUITE_P(
    DamBreak, Stability,
    ::testing::Values(Extreme{"base"},
                      Extreme{"stiffness_x0_1", 0.1f, 1.0f, 1.0f, "sound speed"},
                      Extreme{"stiffness_x100", 100.0f},
                      Extreme{"viscosity_0", 1.0f, 0.0f},
                      Extreme{"viscosity_x100", 1.0f, 100.0f},
                      Extreme{"spacing_x0_5", 1.0f, 1.0f, 0.5f},
                      Extreme{"spacing_x2", 1.0f, 1.0f, 2.0f, "too coarse"},
                      Extreme{"wall_density", 1.0f, 1.0f, 1.0f, nullptr, true},
                      Extreme{"wall_density_viscosity_0", 1.0f, 0.0f, 1.0f, nullptr, true}),
    [](const ::testing::TestParamInfo<Extreme>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace sphxr
