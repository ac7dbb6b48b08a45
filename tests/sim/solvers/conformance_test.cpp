// The conformance suite: what every pressure solver must do, run over every row of the solver table
// (sphxr/sim/solver_table.h SolverTable()), one instance per row named after it (Solvers/Conformance.*/
// wcsph, .../dfsph, .../pbf). A new row is tested by being added to the table: nothing here names a
// method. Each case holds the row to a truth of its own (hydrostatics, the impulse of gravity, the
// energy of the start, a run that was never stopped, the other thread counts, the host reference of the
// CUDA orchestration), within a tolerance whose reason is written beside it. What one method alone
// promises stays in its own file (tests/sim/solvers/wcsph_test.cpp, dfsph_test.cpp, pbf_test.cpp).
//
// Only the public API: sphxr/sim/solver.h, the scene (params.h), the small scenes of tests/support.h and
// tests/sim/test_scenes.h, a paddle from interaction/. The scenes are the small ones of the per-solver
// tests (a few hundred to 2,000 particles), so that the suite takes seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "sim/same_bits.h"
#include "sim/test_scenes.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/measure.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/solver_table.h"
#include "support.h"

namespace sphxr::sim {

// Readable parameters in gtest's output (the row's name, not its bytes).
void PrintTo(const SolverInfo& row, std::ostream* os) { *os << row.name; }

namespace {

namespace support = ::sphxr::test;

constexpr double kG = 9.81;  // m/s^2, the scenes' gravity (SceneSetup's default)

/// A row that does not meet a case yet, with the page that measures it. The case still runs and holds
/// the row to `bound` instead of the case's own; then it reports itself skipped, so that ctest lists the
/// gap on every run. Remove the line when the row meets the case.
struct KnownGap {
  const char* row;
  const char* test;
  double bound;
  const char* why;
};
const KnownGap kKnownGaps[] = {
    {"dfsph", "TheWallsHoldTheWaterWithoutTheClamp", 1e-3,
     "under its CFL step a particle nearing a wall crosses the contact zone within one step and the "
     "Akinci boundary is too soft to stop it: 0.4-0.8 clamps per 1,000 particle-steps on a dam break "
     "(docs/design/dfsph.md, \"Walls under CFL steps\"), where kLeakingClampRate is 0.1"},
};

const KnownGap* GapOf(const SolverInfo& row, const char* test) {
  for (const KnownGap& g : kKnownGaps) {
    if (std::string(g.row) == row.name && std::string(g.test) == test) return &g;
  }
  return nullptr;
}

class Conformance : public ::testing::TestWithParam<SolverInfo> {
 protected:
  /// `scene` under this row's method.
  SceneSetup Under(SceneSetup scene) const {
    scene.method = GetParam().method;
    return scene;
  }
};

/// |(x, y, z)| of a particle's vector field.
float Norm(Vec4 v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

// ---- still water -------------------------------------------------------------------------------------
// tank_rest at 2 cm (10 x 10 x 5 particles, a 0.2 m column in a closed box, tank_rest's viscosity 0.3,
// the walls every row supports), from the lattice: after 1 s the water is at rest and its pressure is the
// weight of the water above. The truth: p = rho0 g (D - y), D = N dx^3 / (floor area) the depth of the
// water at rest density (every row compresses it by about a percent at most, which moves the surface by
// 2 mm and p by 1 % of rho0 g D).
TEST_P(Conformance, StillWaterRestsUnderHydrostaticPressure) {
  const SceneSetup scene = Under(sim::test::SmallRestTank(SceneSetup::WallPressure::kMirrored, 0.3f));
  auto solver = support::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const SolverParams& p = scene.params;
  const double dx = p.spacing, rho0 = p.restDensity;
  const double area = (scene.tank.max.x - scene.tank.min.x) * (scene.tank.max.z - scene.tank.min.z);
  const double depth = solver->FluidCount() * dx * dx * dx / area;
  ASSERT_NEAR(depth, 0.2, 1e-6);
  while (solver->Time() < 1.0) ASSERT_TRUE(support::StepN(*solver, 1));

  // Layer means (one spacing thick, by height) over the next 0.2 s: the lattice's start sets off sound
  // waves (WCSPH's period 4 D / c = 40 ms here) and the implicit solves' iteration noise; 0.2 s of steps
  // averages both out.
  std::map<int, double> pressure, height;
  std::map<int, int> count;
  float fastest = 0.0f;
  while (solver->Time() < 1.2) {
    ASSERT_TRUE(support::StepN(*solver, 1));
    const HostFluid f = support::DownloadFluid(*solver);
    for (size_t i = 0; i < f.size(); ++i) {
      const int layer = static_cast<int>(std::floor(f.position[i].y / dx));
      pressure[layer] += f.pressure[i];
      height[layer] += f.position[i].y;
      ++count[layer];
      fastest = std::max(fastest, Norm(f.velocity[i]));
    }
  }
  // Speeds stay small: every particle slower than half the speed it would gain falling one spacing,
  // sqrt(2 g dx) = 0.63 m/s. A settling lattice moves at a few cm/s (the rows: 0.09-0.14 m/s at most);
  // water that boils or flows is at that speed.
  EXPECT_LT(fastest, 0.5 * std::sqrt(2.0 * kG * dx)) << "the fastest particle between 1 and 1.2 s, m/s";
  EXPECT_EQ(solver->GetTotals().clampedEvents, 0) << "the walls, not the clamp, hold water at rest";

  // Interior layers: a support radius from the surface (an SPH sum there is cut by the air) and from the
  // floor's boundary sheet half a spacing below the floor (the boundary model's own error). The bound,
  // 10 % of the floor's pressure rho0 g D (196 Pa): what is left of the start's ringing over 0.2 s, the
  // kernel sums of a lattice still settling, and PBF's estimate from lambda alone, which reads its top
  // layers 10-20 % low (s_corr carries some of their weight, pbf_test.cpp). Zero pressure fails it by 9x
  // at the lowest interior layer, half the pressure by 4x.
  const double supportRadius = p.supportFactor * dx, sheet = scene.tank.min.y - 0.5 * dx, floorPressure = rho0 * kG * depth;
  int checked = 0;
  for (const auto& [layer, sum] : pressure) {
    const double y = height[layer] / count[layer];
    if (depth - y < supportRadius || y - sheet < supportRadius) continue;
    const double expected = rho0 * kG * (depth - y);
    EXPECT_NEAR(sum / count[layer], expected, 0.1 * floorPressure) << "the layer at y = " << y << " m";
    ++checked;
  }
  EXPECT_GE(checked, 5) << "interior layers of the 10-layer column";
}

// ---- a free splash -----------------------------------------------------------------------------------
// An 8 x 8 x 6 block thrown sideways at 0.5 m/s from 10 cm above the floor of an open 0.3 x 0.3 x 0.2 m
// tank: it flies, lands and splashes for 0.6 s.
// - While no particle is within reach of a wall (a support radius of the boundary sheet, which lies half a
//   spacing behind each face), the only outside force is gravity: every row's fluid forces or position
//   corrections come in antisymmetric pairs, so the momentum is P(0) + M g t to the rounding of the pair
//   sums. Bound: 1e-4 of sum |v| (the rows: 3e-7 to 1e-5; a force that is not a pair force, such as one
//   particle's wrong neighbour list, moves it by a whole term, g dt of one particle, 1e-2 of a particle's
//   speed).
// - Afterwards the floor can only push up (the boundary's pressure and viscosity terms repel along the
//   line between the particles, the contact and the clamp push inward, the friction is along the face):
//   the vertical momentum never falls below P_y(0) - M g t by more than that rounding.
// - The energy does not grow: kinetic plus gravity's potential never exceeds the start's by more than
//   1 % of M g y_cm(0), the potential energy the splash turns over. Symplectic Euler's energy error is
//   about 1/2 dt |v| |a| a unit of mass (1e-3 s x 1.6 m/s x 10 m/s^2 / 2 = 0.008 J/kg at the landing, under
//   1 % of g y_cm = 1.37 J/kg); the rows' internal energy (WCSPH's Tait compression) starts at 0 and is
//   not counted, which only lowers the sum; viscosity and the implicit solves only take energy out.
TEST_P(Conformance, AFreeSplashTakesGravitysImpulseAndGainsNoEnergy) {
  SceneSetup scene = Under(support::TankScene({0, 0, 0}, {0.3f, 0.3f, 0.2f}, 0.01f));
  scene.params.maxDt = 1e-3f;
  scene.fluid.push_back(support::Block({0.08f, 0.1f, 0.07f}, {0.16f, 0.18f, 0.13f}, {0.5f, 0.0f, 0.0f}));
  auto solver = support::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const int n = solver->FluidCount();
  ASSERT_EQ(n, 8 * 8 * 6);
  const double m = solver->ParticleMass(), M = m * n;
  const double reach = solver->SupportRadius() + 0.5 * scene.params.spacing;
  auto energy = [&](const HostFluid& f) {
    double e = 0.0;
    for (size_t i = 0; i < f.size(); ++i) {
      const double v = Norm(f.velocity[i]);
      e += 0.5 * m * v * v + m * kG * f.position[i].y;
    }
    return e;
  };
  auto nearestWall = [&](const HostFluid& f) {
    float d = 1e30f;
    const Aabb& t = scene.tank;
    for (const Vec4& x : f.position) {
      d = std::min({d, x.x - t.min.x, t.max.x - x.x, x.y - t.min.y, x.z - t.min.z, t.max.z - x.z});
    }
    return d;
  };
  HostFluid f = support::DownloadFluid(*solver);
  ASSERT_GT(nearestWall(f), reach) << "the block must start out of the walls' reach";
  const MomentumSummary p0 = Momentum(f);  // per particle mass
  const double e0 = energy(f);
  double yCm = 0.0;
  for (const Vec4& x : f.position) yCm += x.y / n;
  const double energyBound = 0.01 * M * kG * yCm;

  bool free = true;
  int freeSteps = 0;
  while (solver->Time() < 0.6) {
    ASSERT_TRUE(support::StepN(*solver, 1));
    f = support::DownloadFluid(*solver);
    ASSERT_EQ(support::FirstNonFinite(f), "");
    const double t = solver->Time();
    const MomentumSummary p = Momentum(f);
    const double gravityPy = p0.py - n * kG * t;  // P_y(0) - M g t, per particle mass
    const double rounding = 1e-4 * p.sumAbs;
    free = free && nearestWall(f) > reach;
    if (free) {
      ++freeSteps;
      const double off = std::sqrt((p.px - p0.px) * (p.px - p0.px) + (p.py - gravityPy) * (p.py - gravityPy) +
                                   (p.pz - p0.pz) * (p.pz - p0.pz));
      ASSERT_LE(off, rounding) << "in free flight at t = " << t << " s: P - P(0) - M g t, per particle mass (m/s)";
    }
    ASSERT_GE(p.py - gravityPy, -rounding) << "the walls pulled the water down at t = " << t << " s";
    ASSERT_LE(energy(f) - e0, energyBound) << "kinetic + potential energy above the start at t = " << t << " s (J)";
  }
  EXPECT_GT(freeSteps, 10) << "the block should fly before it lands";
  EXPECT_FALSE(free) << "the block should land within 0.6 s";
}

// ---- a paddle pushing water --------------------------------------------------------------------------
// A blade 6 cm wide and 6 cm deep (interaction::BladeOnHandle, its face across x) pushed 10 cm along x at
// 0.5 m/s through a 10 cm pool. The truth is a flat plate in a flow:
// - It feels a resisting force: the mean of F_x over the push is at most -1/2 rho0 U^2 A, the dynamic
//   pressure on the blade's area (Cd >= 1 for a plate across a flow; the bow wave's height and the tank's
//   blockage, 36 % of its section, only add to it). The rows: 2-5x that.
// - The water ahead moves with it: the mean x velocity of the water in the 3 cm before the blade's face is
//   above 0.2 U. Potential flow ahead of a plate of half-width a falls from U at the face to a third of it
//   at a distance a; its mean over the first a (3 cm) is about 0.45 U. The rows: 0.37-0.45 U.
TEST_P(Conformance, APaddlePushesTheWaterAheadAndFeelsItResist) {
  SceneSetup scene = Under(support::TankScene({0, 0, 0}, {0.2f, 0.2f, 0.1f}, 0.01f));
  scene.params.maxDt = 1e-3f;
  scene.fluid.push_back(support::Block({0, 0, 0}, {0.2f, 0.1f, 0.1f}));
  const float blade = 0.06f, thickness = 0.012f;
  RigidBodySetup body;
  body.shapes = interaction::BladeOnHandle(0.06f, 0.01f, thickness, blade, blade);  // x thin, y deep, z wide
  body.points = interaction::SamplePaddle(body.shapes, scene.params.spacing);
  body.pose.position = Vec3{0.05f, 0.14f, 0.05f};  // the blade from y = 0.02 to 0.08 m, z = 0.02 to 0.08 m
  scene.bodies.push_back(body);
  auto solver = support::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const double travel = 0.1, duration = 0.2, U = travel / duration;
  Pose target = solver->BodyPose(0);
  target.position.x += static_cast<float>(travel);
  ASSERT_TRUE(solver->SetBodyTarget(0, target, duration).ok());
  double impulse = 0.0;
  while (solver->Time() < duration - 1e-9) {
    ASSERT_TRUE(support::StepN(*solver, 1));
    impulse += solver->LastBodyLoad(0).force.x * solver->LastStep().dt;
  }
  EXPECT_NEAR(solver->BodyPose(0).position.x, target.position.x, 1e-4f);
  const double dynamic = 0.5 * scene.params.restDensity * U * U * blade * blade;
  EXPECT_LT(impulse / solver->Time(), -dynamic) << "the mean of the fluid's F_x on the blade, N";

  const HostFluid f = support::DownloadFluid(*solver);
  ASSERT_EQ(support::FirstNonFinite(f), "");
  const Vec3 at = solver->BodyPose(0).position;
  const float face = at.x + 0.5f * thickness;
  double sum = 0.0;
  int ahead = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    const Vec4 x = f.position[i];
    if (x.x > face && x.x < face + 0.5f * blade && x.y > 0.02f && x.y < 0.08f && std::fabs(x.z - at.z) < 0.5f * blade) {
      sum += f.velocity[i].x;
      ++ahead;
    }
  }
  ASSERT_GT(ahead, 50) << "water before the blade";
  EXPECT_GT(sum / ahead, 0.2 * U) << "the mean x velocity of the water ahead of the blade, m/s";
}

// ---- walls that hold ---------------------------------------------------------------------------------
// The small dam break in a closed tank for 0.6 s: the column falls, runs along the floor, climbs the far
// wall and falls back. No particle leaves the tank, and the walls hold it, not the clamp behind them: at
// most kLeakingClampRate (1 in 10,000 particle-steps), the rate at which the clamp is a safety net
// (docs/design/walls.md).
TEST_P(Conformance, TheWallsHoldTheWaterWithoutTheClamp) {
  SceneSetup scene = Under(support::SmallDamBreak(0.01f));
  scene.openTop = false;
  auto solver = support::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const int n = solver->FluidCount();
  const Aabb& t = scene.tank;
  while (solver->Time() < 0.6) {
    ASSERT_TRUE(support::StepN(*solver, 1));
    const HostFluid f = support::DownloadFluid(*solver);
    ASSERT_EQ(static_cast<int>(f.size()), n);
    for (const Vec4& x : f.position) {
      ASSERT_TRUE(x.x >= t.min.x && x.x <= t.max.x && x.y >= t.min.y && x.y <= t.max.y && x.z >= t.min.z && x.z <= t.max.z)
          << "a particle left the tank at t = " << solver->Time() << " s: [" << x.x << ", " << x.y << ", " << x.z << "]";
    }
  }
  const Totals& totals = solver->GetTotals();
  const double rate = static_cast<double>(totals.clampedEvents) / static_cast<double>(totals.particleSteps);
  RecordProperty("clamps_per_thousand", std::to_string(1e3 * rate));
  const KnownGap* gap = GapOf(GetParam(), "TheWallsHoldTheWaterWithoutTheClamp");
  EXPECT_LT(rate, gap ? gap->bound : kLeakingClampRate)
      << totals.clampedEvents << " clamps in " << totals.particleSteps << " particle-steps";
  if (gap) GTEST_SKIP() << "known gap, held to " << gap->bound << " instead: " << gap->why;
}

// ---- a restore bit for bit ---------------------------------------------------------------------------
// The small dam break saved after 40 steps and restored into a fresh solver: its next 20 steps are the
// saved solver's own, bit for bit (every backend is deterministic on one thread).
TEST_P(Conformance, ARestoreContinuesTheRunBitForBit) {
  same_bits::ExpectRestoredRunMatches(Under(support::SmallDamBreak(0.01f)));
}

// ---- the same bits at every thread count -------------------------------------------------------------
// The small dam break (10 x 15 x 6 = 900 particles), 200 steps (the column is falling and spreading), on
// 1, 2 (twice: the SIMD stages' guided chunks may split otherwise) and 3 threads (other chunks for
// certain): bit-identical positions, velocities (their w too), time steps and sorted order.
// ctest runs it with OMP_WAIT_POLICY=passive (tests/CMakeLists.txt): with libgomp's default active
// waiting, a 2-thread team on a 2-core machine that another process also uses spins at every barrier.
TEST_P(Conformance, TheSameBitsAtEveryThreadCount) {
  const SceneSetup scene = Under(support::SmallDamBreak(0.01f));
  const same_bits::RunResult one = same_bits::RunScene(scene, 1, 200);
  auto expectWholeVectors = [&](const same_bits::RunResult& other) {
    ASSERT_EQ(one.fluid.size(), other.fluid.size());
    for (size_t i = 0; i < one.fluid.size(); ++i) {
      ASSERT_EQ(one.fluid.id[i], other.fluid.id[i]);
      ASSERT_EQ(std::memcmp(&one.fluid.position[i], &other.fluid.position[i], sizeof(Vec4)), 0) << "particle " << i;
      ASSERT_EQ(std::memcmp(&one.fluid.velocity[i], &other.fluid.velocity[i], sizeof(Vec4)), 0) << "particle " << i;
    }
  };
  for (const int threads : {2, 2, 3}) {
    SCOPED_TRACE("1 and " + std::to_string(threads) + " threads");
    const same_bits::RunResult other = same_bits::RunScene(scene, threads, 200);
    same_bits::ExpectIdentical(one, other);
    expectWholeVectors(other);
  }
}

// ---- cpu against cpu-reference -----------------------------------------------------------------------
// The CPU backend (its SIMD stages) against the host reference of the CUDA orchestration, one step at a
// time from the same state (the reference gets the CPU's state before each step, as in
// tests/backend/agreement_test.cpp: two rounding paths through a splash part ways chaotically, so a
// comparison of whole runs would need a bound that also passes a wrong orchestration). 100 steps of the
// small dam break at the same fixed step, 0.7 of the start's stable step. Bounds, u = 2^-24 the unit
// roundoff of float and n the terms of a particle's sums (fluid in its support sphere and as many wall
// particles, 2 x 4/3 pi s^3 = 67 at support factor s = 2):
// - the densities, sums of positive terms, to n u rho (Higham 2002, eq. 4.4: gamma_n; PBF's are taken
//   at positions one correction apart, which differ by the same rounding);
// - a position to its last bits, 2 u |x|, plus n u of the step's largest displacement (the sums that make
//   the displacement, in another order or with other fused multiply-adds);
// - a velocity to the position's bound over dt (PBF's velocity is the displacement over dt; the others'
//   displacement is dt v).
// Each bound with a safety factor of 4, as the backend suite's. The rows: at most 0.2-0.7 of the bounds
// without it. A missing neighbour moves a density by m W / rho ~ 1/n of it, 10^4 of its bound.
TEST_P(Conformance, CpuAgreesWithCpuReferenceToRounding) {
  constexpr double kUnitRoundoff = 5.9604644775390625e-8;  // 2^-24
  constexpr double kSafety = 4.0;
  SceneSetup scene = Under(support::SmallDamBreak(0.01f));
  SolverConfig cpuConfig = support::TestConfig(), referenceConfig = support::TestConfig();
  cpuConfig.device = Device::kCpu;
  referenceConfig.device = Device::kCpuReference;
  {
    auto probe = support::CreateOrFail(scene, cpuConfig);
    ASSERT_TRUE(probe);
    scene.params.fixedDt = 0.7f * probe->StableDt();
  }
  auto cpu = support::CreateOrFail(scene, cpuConfig);
  auto reference = support::CreateOrFail(scene, referenceConfig);
  ASSERT_TRUE(cpu && reference);
  const double nu = 2.0 * (4.0 / 3.0) * M_PI * std::pow(scene.params.supportFactor, 3.0) * kUnitRoundoff;
  double worst = 0.0;  // the largest difference as a fraction of its bound
  HostFluid before, a, b;
  for (int step = 1; step <= 100; ++step) {
    cpu->Download(&before);
    ASSERT_TRUE(reference->Upload(before).ok());
    ASSERT_TRUE(support::StepN(*cpu, 1) && support::StepN(*reference, 1));
    ASSERT_EQ(cpu->GetTotals().dtClampedSteps, 0) << "the stable step fell below the fixed step at step " << step;
    ASSERT_EQ(cpu->LastStep().dt, reference->LastStep().dt) << "step " << step;
    const double dt = cpu->LastStep().dt;
    cpu->Download(&a);
    reference->Download(&b);
    ASSERT_EQ(a.size(), b.size());
    const auto inB = support::IndexById(b), inBefore = support::IndexById(before);
    double xMax = 0.0, moveMax = 0.0, rhoMax = scene.params.restDensity;
    for (size_t i = 0; i < a.size(); ++i) {
      xMax = std::max(xMax, static_cast<double>(Norm(a.position[i])));
      moveMax = std::max(moveMax, static_cast<double>(Length(Xyz(a.position[i]) - Xyz(before.position[inBefore.at(a.id[i])]))));
      rhoMax = std::max(rhoMax, static_cast<double>(a.density[i]));
    }
    const double posTol = kSafety * (2.0 * kUnitRoundoff * xMax + nu * moveMax);
    const double velTol = posTol / dt;
    const double rhoTol = kSafety * nu * rhoMax;
    for (size_t i = 0; i < a.size(); ++i) {
      const auto it = inB.find(a.id[i]);
      ASSERT_NE(it, inB.end()) << "particle id " << a.id[i] << " missing from the reference";
      const size_t j = it->second;
      const double dx = Length(Xyz(a.position[i]) - Xyz(b.position[j]));
      const double dv = Length(Xyz(a.velocity[i]) - Xyz(b.velocity[j]));
      const double dr = std::fabs(static_cast<double>(a.density[i]) - b.density[j]);
      worst = std::max({worst, dx / posTol, dv / velTol, dr / rhoTol});
      ASSERT_TRUE(dx <= posTol && dv <= velTol && dr <= rhoTol)
          << "step " << step << ", particle id " << a.id[i] << ": |dx| " << dx << " m (bound " << posTol << "), |dv| " << dv
          << " m/s (bound " << velTol << "), |drho| " << dr << " kg/m^3 (bound " << rhoTol << ")";
    }
  }
  RecordProperty("worst_fraction_of_bound", std::to_string(worst));
}

INSTANTIATE_TEST_SUITE_P(Solvers, Conformance, ::testing::ValuesIn(SolverTable().begin(), SolverTable().end()),
                         [](const ::testing::TestParamInfo<SolverInfo>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace sphxr::sim
