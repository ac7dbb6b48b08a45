// Step by step, a backend against the host reference of the CUDA orchestration (cpu-reference): the
// `cpu` backend here, `cuda` where a GPU answers. Four scenes cover the paths where the backends take
// different code: the dam break (density and forces in SIMD against the per-particle stages), the stir
// scene (a moving body: its density and force terms, the reaction, the push-out), the deep tank with
// reuse `balanced` (the compacted lists) and tank_rest with its walls' own density (the wall pressure).
//
// The comparison re-synchronises every step. Two rounding paths through a dam break part ways
// chaotically: after some hundred steps a particle's position differs by more than any bound that
// rounding can justify, and a tolerance wide enough to pass would also pass a wrong orchestration. So
// before each step the tested backend's state is uploaded into the reference, both take the same step
// (the same dt: a fixed step below the stability limit, so that the clocks, and with them the paddle's
// targets, are identical), and the one step's results are compared. The tolerance is then a bound on
// one step's rounding, derived below from the float unit roundoff; a missing neighbour, a particle left
// out of a list or a list one short moves a result by a whole term, orders of magnitude above it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/interaction/paddle.h"
#include "support.h"

namespace sphxr::sim {
namespace {

// One step's rounding bounds. u = 2^-24, the unit roundoff of float. A sum of n terms in another order,
// or with multiply-adds fused differently, differs by at most about n u times the sum of the terms'
// magnitudes (Higham, "Accuracy and Stability of Numerical Algorithms", 2002, eq. 4.4: gamma_n).
//  - n: a particle's terms, fluid within the support sphere (4/3 pi s^3 at support factor s) plus as
//    many wall or body particles (a particle in a corner sees three walls, but thinner ones).
//  - Density: the terms are positive, so |drho| <= n u rho.
//  - Pressure: Tait's dp/drho = c^2 (rho/rho0)^(gamma-1), so |dp| <= c^2 (rho/rho0)^(gamma-1) |drho| + u |p|.
//  - Acceleration: the pressure terms m (p_i/rho_i^2 + p_j/rho_j^2) |grad W| sum, in magnitude, to about
//    (|p| / rho) / h (the integral of |grad W| over the support is of order 1/h). Reordering that sum
//    costs n u times its magnitude. A density difference drho (measured: the largest of the step,
//    itself held to the bound above) moves a pressure by c^2 (rho/rho0)^(gamma-1) drho and so an
//    acceleration by that over rho h. The viscosity, gravity and the walls' and bodies' terms are
//    covered by adding the largest |a| of the step and a safety factor of 4:
//      |da| <= 4 (n u (|p|max / (rho0 h) + |a|max) + c^2 (rho_max/rho0)^(gamma-1) drho_max / (rho0 h)).
//  - Velocity: v' = v + dt a: |dv| <= dt |da| + 2 u |v|. Position: x' = x + dt v': |dx| <= dt |dv| + 2 u |x|.
constexpr double kUnitRoundoff = 5.9604644775390625e-8;  // 2^-24
constexpr double kSafety = 4.0;

struct Errors {
  double position = 0, velocity = 0, acceleration = 0, density = 0;  // worst |difference| / bound, over the run
  double positionAbs = 0, velocityAbs = 0, densityAbs = 0;          // worst |difference| in SI units
  int steps = 0;
};

struct Case {
  const char* name;
  const char* sceneFile;
  float spacing;       // coarser than the scene's: see each case below
  const char* reuse;   // preset, or nullptr
  int steps;
  SolverMethod method = SolverMethod::kWcsph;
};

// The scenes at coarser spacings: 500 steps of both backends then take 1-4 s per case on one core
// (the whole file under 15 s), where the full scenes would take minutes (the deep tank alone is 52,000
// particles). The paths compared depend on the kinds of particles present (walls, a body, particles
// that reuse), not on their number.
const Case kCases[] = {
    {"dam_break", "dam_break.json", 0.005f, nullptr, 500},     // 11 x 22 x 4 = 1,000 particles
    {"stir_paddle", "stir.json", 0.02f, nullptr, 500},         // ~1,700 particles and the paddle
    {"deep_tank_balanced", "deep_tank.json", 0.05f, "balanced", 500},  // 16 x 14 x 14 pool and a 4^3 drop
    {"tank_rest_wall_density", "tank_rest.json", 0.02f, nullptr, 500},  // 10 x 10 x 5 in a closed box
    {"dam_break_pbf", "dam_break.json", 0.005f, nullptr, 300, SolverMethod::kPbf},  // the bound below
    {"stir_paddle_pbf", "stir.json", 0.02f, nullptr, 300, SolverMethod::kPbf},
};

struct Pair {
  Device tested;
  const char* name;
};

// Readable parameters in gtest's and ctest's output.
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }
void PrintTo(const Pair& p, std::ostream* os) { *os << p.name; }

class BackendAgreement : public ::testing::TestWithParam<std::tuple<Pair, Case>> {};

// The run as every mode builds it (app::Simulation: the scene's paddles, the solver, the paddle clock).
struct Rig {
  std::unique_ptr<app::Simulation> run;
  Solver* solver = nullptr;
};

Rig Make(const app::SceneFile& file, const SceneSetup& setup, Device device) {
  Rig r;
  app::SimScene scene = app::SimSceneFromFile(file);
  scene.setup = setup;
  app::SimulationConfig config;
  config.solver = test::TestConfig();
  config.solver.device = device;
  const Status s = app::Simulation::Create(scene, config, &r.run);
  EXPECT_TRUE(s.ok()) << s.message();
  if (r.run) r.solver = &r.run->Solver();
  return r;
}

float Dist(Vec4 a, Vec4 b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)); }
float Len(Vec4 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

TEST_P(BackendAgreement, OneStepFromTheSameStateAgreesToRounding) {
  const Pair pair = std::get<0>(GetParam());
  const Case c = std::get<1>(GetParam());
  if (pair.tested == Device::kCuda && CudaDeviceCount() == 0) GTEST_SKIP() << "no CUDA device";

  app::SceneFile file;
  ASSERT_TRUE(app::LoadScene(std::string(SPHXR_SCENES_DIR "/") + c.sceneFile, &file).ok());
  SceneSetup setup = file.setup;
  setup.params.spacing = c.spacing;
  setup.method = c.method;
  if (c.reuse) {
    ASSERT_TRUE(ApplyReusePreset(c.reuse, &setup.reuse));
  }
  // The same dt on both: a fixed step at 0.7 of the start's stability limit (which the flow's speed
  // and acceleration lower a little as it moves; a step where the limit fell below it fails the test).
  {
    Rig probe = Make(file, setup, Device::kCpu);
    ASSERT_TRUE(probe.solver);
    const float fixed = setup.params.fixedDt > 0.0f ? std::min(setup.params.fixedDt, probe.solver->StableDt())
                                                     : probe.solver->StableDt();
    setup.params.fixedDt = 0.7f * fixed;
  }
  Rig tested = Make(file, setup, pair.tested);
  Rig reference = Make(file, setup, Device::kCpuReference);
  ASSERT_TRUE(tested.solver && reference.solver);
  ASSERT_EQ(tested.solver->FluidCount(), reference.solver->FluidCount());
  SCOPED_TRACE(Format("%s: %d fluid particles, spacing %g m, dt %g s", c.name, tested.solver->FluidCount(), c.spacing,
                      setup.params.fixedDt));

  const SolverParams& p = setup.params;
  const double rho0 = p.restDensity;
  const double c0 = tested.solver->SoundSpeed();
  const double h = 0.5 * p.spacing * p.supportFactor;
  const double n = 2.0 * (4.0 / 3.0) * M_PI * std::pow(p.supportFactor, 3.0);
  const double nu = n * kUnitRoundoff;

  Errors worst;
  float leastActive = 1.0f;  // under reuse: the compacted lists must have been exercised
  double worstLoad = 0.0;    // the body's load, as a fraction of its bound
  HostFluid before, a, b;
  for (int step = 1; step <= c.steps; ++step) {
    tested.solver->Download(&before);
    ASSERT_TRUE(reference.solver->Upload(before).ok());
    // (Both paddle clocks give the same frames: the same start and the same dt on both.)
    const Status testedStep = tested.run->Step(), referenceStep = reference.run->Step();
    ASSERT_TRUE(testedStep.ok()) << "step " << step << ": " << testedStep.message();
    ASSERT_TRUE(referenceStep.ok()) << "step " << step << ": " << referenceStep.message();
    ASSERT_EQ(tested.solver->GetTotals().dtClampedSteps, 0) << "the stability limit fell below the fixed step at step " << step;
    ASSERT_EQ(tested.solver->LastStep().dt, reference.solver->LastStep().dt) << "step " << step;
    // Under reuse the same particles compute: the classification reads the uploaded state only.
    ASSERT_EQ(tested.solver->LastStep().activeFraction, reference.solver->LastStep().activeFraction)
        << "step " << step << ": a different number of particles computed";
    leastActive = std::min(leastActive, tested.solver->LastStep().activeFraction);

    tested.solver->Download(&a);
    reference.solver->Download(&b);
    ASSERT_EQ(a.size(), b.size());
    // The bound's scales, from this step's results.
    double pMax = 0, aMax = 0, vMax = 0, xMax = 0, rhoMax = rho0;
    for (size_t i = 0; i < a.size(); ++i) {
      pMax = std::max(pMax, std::fabs(static_cast<double>(a.pressure[i])));
      aMax = std::max(aMax, static_cast<double>(Len(a.acceleration[i])));
      vMax = std::max(vMax, static_cast<double>(Len(a.velocity[i])));
      xMax = std::max(xMax, static_cast<double>(Len(a.position[i])));
      rhoMax = std::max(rhoMax, static_cast<double>(a.density[i]));
    }
    const double dt = tested.solver->LastStep().dt;
    const double rhoTol = c.method == SolverMethod::kPbf
                              ? nu * rhoMax + rho0 * kSafety * std::pow(2.0, p.pbfIterations + 1.0) * nu
                              : nu * rhoMax;
    const auto byId = test::IndexById(b);
    double dRhoMax = 0.0;  // the density differences found (each also held to rhoTol below)
    for (size_t i = 0; i < a.size(); ++i) {
      const auto it = byId.find(a.id[i]);
      ASSERT_NE(it, byId.end()) << "particle id " << a.id[i] << " missing from the reference";
      dRhoMax = std::max(dRhoMax, std::fabs(static_cast<double>(a.density[i]) - b.density[it->second]));
    }
    double accelTol =
        kSafety * (nu * (pMax / rho0 / h + aMax) + c0 * c0 * std::pow(rhoMax / rho0, p.exponent - 1.0) * (dRhoMax / rho0) / h);
    double velTol = dt * accelTol + 2.0 * kUnitRoundoff * vMax;
    double posTol = dt * velTol + 2.0 * kUnitRoundoff * xMax;
    if (c.method == SolverMethod::kPbf) {
      // PBF moves positions, and its velocity and acceleration follow from them. An iteration's
      // correction is a Newton step on C = rho/rho0 - 1, whose sums are good to n u: it moves a particle
      // by n u h at most, and the Jacobi sum over a particle's constraints can double what the last
      // iteration left (the relaxation keeps it below that), so K iterations leave 2^(K+1) n u h. Then
      // v = dx / dt, a = dv / dt, and the density of the last iteration (at the positions before its
      // correction) moves by rho0 |grad C| dx, |grad C| ~ 1/h, besides its own n u rho.
      const double iterations = p.pbfIterations;
      posTol = kSafety * std::pow(2.0, iterations + 1.0) * nu * h + 2.0 * kUnitRoundoff * xMax;
      velTol = posTol / dt + 2.0 * kUnitRoundoff * vMax;
      accelTol = velTol / dt + 2.0 * kUnitRoundoff * aMax;
    }
    for (size_t i = 0; i < a.size(); ++i) {
      const size_t j = byId.at(a.id[i]);
      const double dx = Dist(a.position[i], b.position[j]);
      const double dv = Dist(a.velocity[i], b.velocity[j]);
      const double da = Dist(a.acceleration[i], b.acceleration[j]);
      const double dr = std::fabs(static_cast<double>(a.density[i]) - b.density[j]);
      worst.position = std::max(worst.position, dx / posTol);
      worst.velocity = std::max(worst.velocity, dv / velTol);
      worst.acceleration = std::max(worst.acceleration, da / accelTol);
      worst.density = std::max(worst.density, dr / rhoTol);
      worst.positionAbs = std::max(worst.positionAbs, dx);
      worst.velocityAbs = std::max(worst.velocityAbs, dv);
      worst.densityAbs = std::max(worst.densityAbs, dr);
      if (dx > posTol || dv > velTol || da > accelTol || dr > rhoTol) {
        FAIL() << "step " << step << ", particle id " << a.id[i] << ": |dx| " << dx << " m (bound " << posTol
               << "), |dv| " << dv << " m/s (bound " << velTol << "), |da| " << da << " m/s^2 (bound " << accelTol
               << "), |drho| " << dr << " kg/m^3 (bound " << rhoTol << "); density " << a.density[i] << " against "
               << b.density[j] << ", idle " << a.idle[i] << " against " << b.idle[j];
      }
    }
    // The paddle's load: the sum over its particles of the reactions, each bounded as a particle's
    // acceleration times a particle's mass.
    for (int k = 0; k < tested.solver->BodyCount(); ++k) {
      std::vector<Vec4> bodyPos, bodyVel;
      tested.solver->DownloadBodies(&bodyPos, &bodyVel);
      const Vec3 fa = tested.solver->LastBodyLoad(k).force, fb = reference.solver->LastBodyLoad(k).force;
      const double df = Length(fa - fb);
      const double loadTol = static_cast<double>(bodyPos.size()) * tested.solver->ParticleMass() * accelTol;
      worstLoad = std::max(worstLoad, df / loadTol);
      ASSERT_LE(df, loadTol) << "step " << step << ": the paddle's load " << fa.x << ", " << fa.y << ", " << fa.z
                             << " N against " << fb.x << ", " << fb.y << ", " << fb.z << " N";
    }
    worst.steps = step;
  }
  if (setup.reuse.enabled) {
    EXPECT_LT(leastActive, 0.9f) << "reuse never skipped a tenth of the particles";
  }
  // For the record (ctest --output-on-failure, scripts/gpu_check.sh): the largest difference as a
  // fraction of its bound, and in SI units.
  std::printf("[agreement] %s %s vs cpu-reference, %d steps: worst |dx| %.3g m (%.3g of bound), |dv| %.3g m/s (%.3g), "
              "|da| (%.3g of bound), |drho| %.3g kg/m^3 (%.3g), body load (%.3g of bound), least active %.2f\n",
              c.name, pair.name, worst.steps, worst.positionAbs, worst.position, worst.velocityAbs, worst.velocity,
              worst.acceleration, worst.densityAbs, worst.density, worstLoad, leastActive);
  RecordProperty("worst_position_m", std::to_string(worst.positionAbs));
  RecordProperty("worst_velocity_fraction_of_bound", std::to_string(worst.velocity));
}

std::string Name(const ::testing::TestParamInfo<BackendAgreement::ParamType>& info) {
  return std::string(std::get<0>(info.param).name) + "_" + std::get<1>(info.param).name;
}

INSTANTIATE_TEST_SUITE_P(Scenes, BackendAgreement,
                         ::testing::Combine(::testing::Values(Pair{Device::kCpu, "cpu"}, Pair{Device::kCuda, "cuda"}),
                                            ::testing::ValuesIn(kCases)),
                         Name);

}  // namespace
}  // namespace sphxr::sim
