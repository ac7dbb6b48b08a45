// The dam break of scenes/dam_break.json against the measurements of Martin & Moyce (1952),
// tests/data/martin_moyce_1952.csv (a copy of shared/data): surge front Z(T) and residual column
// height H(tau). The front ignores spray (app::DamBreakMinPerBin, sim::ConnectedExtent). The
// experiment's gate lag is one time shift for both series, found by sim::JudgeMartinMoyce.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sphxr/app/scene_file.h"
#include "sphxr/sim/measure.h"
#include "sphxr/sim/solver.h"

namespace sphxr {
namespace {

// The same bounds with reuse off (the core solver), with the `balanced` reuse preset, under DFSPH, and
// under PBF at its defaults (3 substeps of 3 iterations a 90 Hz frame, XSPH c = 0.01).
class DamBreak : public ::testing::TestWithParam<const char*> {};

TEST_P(DamBreak, MatchesMartinMoyce1952) {
  std::vector<sim::DamBreakPoint> measuredFront, measuredHeight;
  ASSERT_TRUE(sim::ReadMartinMoyce(SPHXR_TEST_DATA_DIR "/martin_moyce_1952.csv", &measuredFront, &measuredHeight))
      << "tests/data/martin_moyce_1952.csv missing or malformed";

  app::SceneFile scene;
  ASSERT_TRUE(app::LoadScene(SPHXR_SCENES_DIR "/dam_break.json", &scene).ok());
  scene.setup.params.diffuse = 0.0f;  // the water is the same bits without its spray (DiffuseTest), at less cost
  const std::string preset = GetParam();
  if (preset == "dfsph") {
    scene.setup.method = sim::SolverMethod::kDfsph;  // the same bounds under the divergence-free solver
  } else if (preset == "pbf") {
    scene.setup.method = sim::SolverMethod::kPbf;  // and under position-based fluids
  } else if (preset != "off") {
    ASSERT_TRUE(sim::ApplyReusePreset(preset, &scene.setup.reuse));
  }
  ASSERT_TRUE(scene.damBreak.has_value());
  const app::DamBreakProbe probe = *scene.damBreak;
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(scene.setup, sim::SolverConfig{}, &solver).ok());
  const float dx = scene.setup.params.spacing;
  const double a = probe.columnWidth, g = 9.81;
  const int minPerBin = app::DamBreakMinPerBin(probe, dx);

  // Simulated Z and H, sampled every step.
  std::vector<sim::DamBreakSample> samples;
  const double tEnd = 3.05 / std::sqrt(g / a);  // tau = 3 plus a margin; covers T = 3.33 as well
  sim::HostFluid host;
  const int n = solver->FluidCount();
  while (solver->Time() < tEnd) {
    ASSERT_TRUE(solver->Step().ok());
    ASSERT_TRUE(std::isfinite(solver->LastStep().maxSpeed)) << "non-finite at t = " << solver->Time();
    solver->Download(&host);
    samples.push_back({solver->Time(), sim::SurgeFront(host, probe.wallX, dx, minPerBin) / a,
                       sim::ColumnHeight(host, probe.floorY, probe.wallX, dx, std::max(1, minPerBin / 2)) / (2.0 * a)});
  }
  EXPECT_EQ(static_cast<int>(host.size()), n) << "particles lost";
  // WCSPH's walls hold the water: the clamp behind them is a safety net (docs/design/walls.md). DFSPH's
  // do not yet here: its CFL step lets a fast particle cross the walls' contact zone within one step
  // (0.84 clamps per 1,000 particle-steps at the default tolerance; docs/design/dfsph.md). Recorded, not bounded.
  const sim::Totals& totals = solver->GetTotals();
  const double clampRate = static_cast<double>(totals.clampedEvents) / static_cast<double>(totals.particleSteps);
  RecordProperty("clamps_per_thousand", std::to_string(1e3 * clampRate));
  if (preset != "dfsph") {
    EXPECT_LT(clampRate, sim::kLeakingClampRate)
        << totals.clampedEvents << " clamps in " << totals.particleSteps << " particle-steps";
  }
  if (preset == "balanced") {
    RecordProperty("mean_active_fraction", std::to_string(solver->LastStep().activeFraction));
  }

  // The experiment's gate: one lag for both series, found by the shared judge (sim/measure.h). It must
  // lie strictly inside [0, the experiment's first front time]: at 0 the simulation would be slower than
  // the experiment, which a late gate cannot explain.
  sim::DamBreakJudgement j;
  ASSERT_TRUE(sim::JudgeMartinMoyce(samples, measuredFront, measuredHeight, a, g, &j));
  RecordProperty("gate_lag_ms", std::to_string(1e3 * j.lag));
  EXPECT_GT(j.lag, 0.0) << "the simulation is slower than the experiment";
  EXPECT_LT(j.lag, j.lagLimit) << "no lag within the experiment's first " << 1e3 * j.lagLimit << " ms lines it up";
  ASSERT_GT(j.front.size(), 5u);
  for (const auto& d : j.front) {
    EXPECT_LE(std::fabs(d.relative), 0.12) << "surge front at T = " << d.t << " (lag " << 1e3 * j.lag
                                            << " ms): simulated Z = " << d.simulated << ", measured " << d.measured;
  }
  EXPECT_LE(j.frontRms, 0.08) << "RMS relative deviation of the surge front over 1 <= T <= 3.3";
  RecordProperty("front_rms_percent", std::to_string(100.0 * j.frontRms));
  ASSERT_GT(j.height.size(), 5u);
  for (const auto& d : j.height) {
    EXPECT_LE(std::fabs(d.relative), 0.10) << "column height at tau = " << d.t << " (lag " << 1e3 * j.lag
                                            << " ms): simulated H = " << d.simulated << ", measured " << d.measured;
  }
}

INSTANTIATE_TEST_SUITE_P(Reuse, DamBreak, ::testing::Values("off", "balanced", "dfsph"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

// PBF at its defaults misses the column height (docs/dev/physics.md, PBF). Measured with the free-slip
// scene and the gate judge: lag 3.4 ms, the front within its bounds (max 11.1 %, RMS 7.1 %), but the
// column height +14 ... +81 % from tau = 1.66. Three causes: 3 x 3 iterations a frame cannot hold the
// 40-layer column (the back corner reaches 1.6 rho0, its release gains 46 % of the energy and jets up
// the back wall), s_corr lifts the surface and holds a film on the wall, and with neither (10 x 6
// iterations, pbf_corr_k 0) the column still drains slower than WCSPH's (H +11 ... +22 % from tau = 2):
// the walls move a particle by lambda_i B_i, half a fluid neighbour's share. Mirroring lambda there
// meets every bound at 3 x 6 iterations but keeps still water from calming (81 mm/s; physics.md).
INSTANTIATE_TEST_SUITE_P(DISABLED_Pbf, DamBreak, ::testing::Values("pbf"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

}  // namespace
}  // namespace sphxr
