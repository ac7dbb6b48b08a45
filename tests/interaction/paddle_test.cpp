// Paddles in water: momentum transfer and drag, no fluid inside after a fast swing, teleports and
// tracking loss, deterministic replay; the paddles never step the solver. Small tanks (a few thousand
// particles, CPU backend, one thread).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include "sphxr/interaction/paddle.h"
#include "sphxr/interaction/trajectory.h"
#include "sphxr/sim/solver.h"
#include "refusal.h"
#include "support.h"

namespace sphxr::interaction {
namespace {

using sim::Vec3;
using sim::Vec4;

constexpr double kFrame = 1.0 / 90.0;  // display frames of a headset

/// A 0.3 x 0.2 x 0.12 m tank with water 0.1 m deep (3,600 lattice sites at 1 cm).
sim::SceneSetup SmallTank(float spacing = 0.01f, float stiffness = 50000.0f) {
  sim::SceneSetup s = test::TankScene({0, 0, 0}, {0.3f, 0.2f, 0.12f}, spacing);
  s.params.stiffness = stiffness;
  s.params.viscosity = 0.1f;
  s.params.boundaryViscosity = 0.1f;
  s.params.maxDt = 1e-3f;
  s.fluid.push_back(test::Block({0, 0, 0}, {0.3f, 0.1f, 0.12f}));
  return s;
}

/// A flat blade facing x (1.2 cm thick, 8 cm tall, 6 cm wide) under a vertical handle; the origin is
/// the top of the blade.
std::vector<sim::ShapePrimitive> Blade() {
  sim::ShapePrimitive blade;
  blade.kind = sim::ShapePrimitive::Kind::kBox;
  blade.a = Vec3{0.0f, -0.04f, 0.0f};
  blade.b = Vec3{0.006f, 0.04f, 0.03f};
  sim::ShapePrimitive handle;
  handle.kind = sim::ShapePrimitive::Kind::kCapsule;
  handle.a = Vec3{0.0f, 0.0f, 0.0f};
  handle.b = Vec3{0.0f, 0.1f, 0.0f};
  handle.radius = 0.008f;
  return {blade, handle};
}

TrajectoryKey Key(double t, Vec3 p, bool tracked = true) {
  TrajectoryKey k;
  k.time = t;
  k.pose.position = p;
  k.tracked = tracked;
  return k;
}

/// Paddles on a solver, with the frame loop written out here (the paddles never step the solver; in the
/// program app::Simulation::AdvanceFrame is this loop): a frame every kFrame from the solver's start.
struct Rig {
  std::unique_ptr<PaddleSystem> paddles;
  std::unique_ptr<sim::Solver> solver;
  double nextFrame = 0.0;  // the first step at or past it begins a frame

  /// Steps until the solver's time reaches `time`: BeginFrame with `hands` at each frame, the step,
  /// AfterStep.
  Status Advance(double time, const std::vector<HandInput>& hands = {}) {
    while (solver->Time() < time - 1e-9) {
      if (solver->Time() >= nextFrame - 1e-9) {
        nextFrame += kFrame;
        std::vector<HandInput> framed = hands;
        for (HandInput& h : framed) h.time = nextFrame;
        if (Status s = paddles->BeginFrame(nextFrame, framed); !s) return s;
      }
      if (Status s = solver->Step(); !s) return s;
      paddles->AfterStep();
    }
    return Status::Ok();
  }
};

/// A solver with the given paddles (scripted or hand-held), or a failed test.
Rig MakeRig(sim::SceneSetup scene, std::vector<PaddleDesc> descs) {
  Rig rig;
  const Status s = PaddleSystem::Create(std::move(descs), scene, &rig.paddles);
  EXPECT_TRUE(s.ok()) << s.message();
  if (!s) return rig;
  rig.paddles->AddBodies(&scene);
  rig.solver = test::CreateOrFail(scene);
  if (!rig.solver) return rig;
  const Status a = rig.paddles->Attach(rig.solver.get());
  EXPECT_TRUE(a.ok()) << a.message();
  rig.nextFrame = rig.solver->Time();
  return rig;
}

PaddleDesc Scripted(std::vector<TrajectoryKey> keys) {
  PaddleDesc d;
  d.name = "blade";
  d.shapes = Blade();
  const Status s = Trajectory::FromKeys(std::move(keys), &d.trajectory);
  EXPECT_TRUE(s.ok()) << s.message();
  return d;
}

double FluidMomentumX(const sim::HostFluid& f, double mass, double* pz = nullptr) {
  double px = 0.0, z = 0.0;
  for (const Vec4& v : f.velocity) {
    px += mass * v.x;
    z += mass * v.z;
  }
  if (pz) *pz = z;
  return px;
}

float MaxSpeed(const sim::HostFluid& f) {
  float m = 0.0f;
  for (const Vec4& v : f.velocity) m = std::max(m, std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z));
  return m;
}

/// Fluid particles whose centre is inside body 0's solid (signed distance < 0).
int ParticlesInside(const sim::Solver& solver, const sim::HostFluid& f) {
  int inside = 0;
  for (const Vec4& x : f.position) inside += solver.BodyDistance(0, Xyz(x)) < 0.0f ? 1 : 0;
  return inside;
}

// ---- sampling ---------------------------------------------------------------------------------------

TEST(PaddleSampling, SheetHalfASpacingInsideTheSurfaceAndNoGaps) {
  const float dx = 0.01f;
  const std::vector<sim::ShapePrimitive> shapes = BladeOnHandle();
  const std::vector<Vec3> pts = SamplePaddle(shapes, dx);
  ASSERT_GT(pts.size(), 100u);
  for (const Vec3& p : pts) {
    Vec3 n;
    const float d = sim::UnionDistance(shapes.data(), static_cast<int>(shapes.size()), p, &n);
    EXPECT_NEAR(d, -0.5f * dx, 0.26f * dx) << "a boundary particle is not on the sheet half a spacing inside";
  }
  // Every point of the solid's surface has a boundary particle within a spacing (no hole a fluid
  // particle could pass): checked on a brute-force grid of surface points of the blade's big faces.
  const sim::ShapePrimitive& blade = shapes[1];
  for (float x = -blade.b.x; x <= blade.b.x; x += 0.003f) {
    for (float y = -blade.b.y; y <= blade.b.y; y += 0.003f) {
      const Vec3 q = blade.a + Vec3{x, y, blade.b.z};
      float nearest = 1e9f;
      for (const Vec3& p : pts) nearest = std::min(nearest, Length(p - q));
      EXPECT_LT(nearest, dx) << "hole in the sampling near " << q.x << ", " << q.y << ", " << q.z;
    }
  }
}

// ---- the frame clock is the caller's -----------------------------------------------------------------

// The paddles take targets (BeginFrame) and read loads (AfterStep); the step loop is app::Simulation's.
template <typename T>
concept StepsTheSolver = requires(T& p) { p.Step(); } || requires(T& p) { p.Advance(1.0); };
static_assert(!StepsTheSolver<PaddleSystem>, "the paddles never step the solver: app::Simulation does");

TEST(PaddleSystem, BeginFrameAndAfterStepNeverStepTheSolver) {
  PaddleDesc d;
  d.holder = Holder::kRightHand;
  d.shapes = Blade();
  Rig rig = MakeRig(SmallTank(0.02f), {d});
  ASSERT_TRUE(rig.solver);
  HandInput hand;
  hand.tracked = true;
  hand.pose.position = Vec3{0.1f, 0.12f, 0.06f};
  ASSERT_TRUE(rig.paddles->BeginFrame(kFrame, {HandInput{}, hand}).ok());
  rig.paddles->AfterStep();
  EXPECT_EQ(rig.solver->GetTotals().steps, 0);
  EXPECT_EQ(rig.solver->Time(), 0.0);
  EXPECT_EQ(rig.paddles->State(0).mode, PaddleMode::kReentering) << "the frame took the hand as its target";
}

// ---- pushing and dragging ---------------------------------------------------------------------------

struct SweepResult {
  double momentumX = 0.0;   // fluid momentum along x at the end, kg m/s
  double momentumZ = 0.0;
  double meanDragX = 0.0;   // mean x force of the fluid on the paddle over the middle half of the sweep, N
  double impulseX = 0.0;    // impulse the paddle gave the fluid along x over the sweep, N s
  int64_t pushed = 0;
};

/// The blade starts at x = 0.07 in water at rest, waits 0.05 s, then moves at `speed` to x = 0.19.
SweepResult Sweep(float speed) {
  SweepResult r;
  const double start = 0.05, travel = 0.12;
  const double end = start + (speed > 0.0f ? travel / speed : 0.2);
  const Vec3 a{0.07f, 0.12f, 0.06f};
  const Vec3 b = speed > 0.0f ? Vec3{0.19f, 0.12f, 0.06f} : a;
  // 1.5 cm spacing (about 1,100 particles), sound speed 12 m/s (Mach 0.08 at the faster sweep).
  Rig rig = MakeRig(SmallTank(0.015f, 20000.0f), {Scripted({Key(0.0, a), Key(start, a), Key(end, b)})});
  if (!rig.solver) return r;
  const double mass = rig.solver->ParticleMass();
  int samples = 0;
  for (double t = kFrame; t < end + 1e-9; t += kFrame) {
    if (!rig.paddles->BeginFrame(t).ok()) {
      ADD_FAILURE();
      return r;
    }
    while (rig.solver->Time() < t - 1e-9) {
      if (!test::StepN(*rig.solver, 1)) return r;
      rig.paddles->AfterStep();
      const double now = rig.solver->Time();
      const float fx = rig.solver->LastBodyLoad(0).force.x;
      if (now > start) r.impulseX += -fx * rig.solver->LastStep().dt;
      if (now > start + 0.25 * (end - start) && now < start + 0.75 * (end - start)) {
        r.meanDragX += fx;
        ++samples;
      }
    }
  }
  r.meanDragX /= std::max(1, samples);
  const sim::HostFluid f = test::DownloadFluid(*rig.solver);
  EXPECT_EQ(test::FirstNonFinite(f), "");
  r.momentumX = FluidMomentumX(f, mass, &r.momentumZ);
  r.pushed = rig.solver->GetTotals().pushedOutEvents;
  return r;
}

TEST(PaddleFluid, SweepPushesWaterAlongAndDragGrowsWithSpeed) {
  // Side by side with the blade held still (the same particles, the same settling of the lattice).
  const SweepResult still = Sweep(0.0f);
  const SweepResult slow = Sweep(0.5f);
  const SweepResult fast = Sweep(1.0f);
  std::printf("still: Px %.5f drag %.4f N | 0.5 m/s: Px %.5f Pz %.5f drag %.4f N impulse %.5f pushed %lld | "
              "1 m/s: Px %.5f Pz %.5f drag %.4f N impulse %.5f pushed %lld\n",
              still.momentumX, still.meanDragX, slow.momentumX, slow.momentumZ, slow.meanDragX, slow.impulseX,
              static_cast<long long>(slow.pushed), fast.momentumX, fast.momentumZ, fast.meanDragX, fast.impulseX,
              static_cast<long long>(fast.pushed));
  for (const SweepResult* r : {&slow, &fast}) {
    const double gained = r->momentumX - still.momentumX;
    // The water gained momentum in the direction of motion, more than sideways (the tank is 8 particles
    // wide: the wake sloshes sideways; measured ratio 3.4 at 0.5 m/s, 7 at 1 cm spacing).
    EXPECT_GT(gained, 0.0);
    EXPECT_GT(gained, 2.0 * std::abs(r->momentumZ - still.momentumZ));
    // The fluid resists the motion: its force on the paddle points against it.
    EXPECT_LT(r->meanDragX, 0.0);
  }
  // Drag grows with speed. The artificial viscosity (alpha 0.1) gives nu = alpha c h / 8 = 2.3e-3 m^2/s, a
  // Reynolds number of about 25 for this 6 cm blade at 1 m/s: between Stokes drag (linear: doubling the
  // speed doubles it) and pressure drag (quadratic: x4). Measured x2.2 at 1.5 cm and x2.5 at 1 cm
  // spacing; we ask for x1.8, clearly more than a constant drag and close to the linear bound.
  EXPECT_GT(-fast.meanDragX, 1.8 * -slow.meanDragX);
  EXPECT_GT(fast.momentumX - still.momentumX, slow.momentumX - still.momentumX);
}

// ---- fast swing -------------------------------------------------------------------------------------

/// The blade crosses the tank (0.16 m) at 5 m/s through `scene`'s water: no fluid particle is inside it
/// after any step, nothing becomes non-finite, and the blade keeps to its script.
void SwingAtFiveMetresPerSecond(const sim::SceneSetup& scene) {
  const Vec3 a{0.07f, 0.12f, 0.06f}, b{0.23f, 0.12f, 0.06f};
  const double start = 0.03, end = start + 0.16 / 5.0;
  Rig rig = MakeRig(scene, {Scripted({Key(0.0, a), Key(start, a), Key(end, b)})});
  ASSERT_TRUE(rig.solver);
  float bodySpeed = 0.0f, maxDt = 0.0f;
  int worst = 0;
  for (double t = kFrame; t < end + 3 * kFrame; t += kFrame) {
    ASSERT_TRUE(rig.paddles->BeginFrame(t).ok());
    while (rig.solver->Time() < t - 1e-9) {
      ASSERT_TRUE(test::StepN(*rig.solver, 1));
      rig.paddles->AfterStep();
      bodySpeed = std::max(bodySpeed, Length(rig.solver->BodyVelocity(0)));
      maxDt = std::max(maxDt, rig.solver->LastStep().dt);
      worst = std::max(worst, ParticlesInside(*rig.solver, test::DownloadFluid(*rig.solver)));
    }
  }
  const sim::HostFluid f = test::DownloadFluid(*rig.solver);
  ASSERT_EQ(test::FirstNonFinite(f), "");
  // A step that ends past a frame's time starts the next frame's segment late, so the blade covers it in
  // up to one step less than a frame: at most 5 frame / (frame - dt) m/s.
  EXPECT_GE(bodySpeed, 4.95f) << "the blade did not swing at 5 m/s";
  EXPECT_LE(bodySpeed, 5.0 * kFrame / (kFrame - maxDt) + 0.05) << "the blade did not swing at 5 m/s";
  EXPECT_NEAR(rig.solver->BodyPose(0).position.x, b.x, 1e-5f);
  EXPECT_EQ(worst, 0) << "fluid particles inside the paddle after a step";
  std::printf("5 m/s swing: %lld particle pushes over %lld steps (%d fluid particles), max fluid speed %.2f m/s\n",
              static_cast<long long>(rig.solver->GetTotals().pushedOutEvents),
              static_cast<long long>(rig.solver->GetTotals().steps), rig.solver->FluidCount(), MaxSpeed(f));
}

TEST(PaddleFluid, FiveMetresPerSecondSwingLeavesNoParticleInside) {
  // A stiffer fluid (sound speed 37 m/s, 7x the swing) so that the water, not the push-out, does most of
  // the work.
  SwingAtFiveMetresPerSecond(SmallTank(0.01f, 200000.0f));
}

TEST(PaddleFluid, FiveMetresPerSecondSwingThroughDfsphWaterLeavesNoParticleInside) {
  sim::SceneSetup scene = SmallTank(0.01f, 200000.0f);  // (the stiffness sets only the viscosity's speed scale)
  scene.method = sim::SolverMethod::kDfsph;
  SwingAtFiveMetresPerSecond(scene);
}

TEST(PaddleFluid, FiveMetresPerSecondSwingThroughPbfWaterLeavesNoParticleInside) {
  // PBF steps a third of a 90 Hz frame (3.7 ms): the blade moves 1.9 cm a step, more than its 1.2 cm
  // thickness, so the push-out at the step's end pose takes much of the work from the constraint.
  sim::SceneSetup scene = SmallTank(0.01f, 200000.0f);  // (the stiffness sets only WCSPH's speed scale)
  scene.method = sim::SolverMethod::kPbf;
  SwingAtFiveMetresPerSecond(scene);
}

// ---- teleport ---------------------------------------------------------------------------------------

TEST(PaddleFluid, OneMetreTeleportIsNotAHugeVelocity) {
  // A hand-held paddle follows the hand in the water, then the hand jumps 1 m (re-tracking) in one frame,
  // stays there 0.2 s, and jumps back into the water.
  sim::SceneSetup scene = SmallTank(0.015f, 20000.0f);
  PaddleDesc d;
  d.name = "right";
  d.holder = Holder::kRightHand;
  d.shapes = Blade();
  Rig rig = MakeRig(scene, {d});
  ASSERT_TRUE(rig.solver);
  const PaddleLimits limits;
  HandInput hand;
  hand.tracked = true;
  const Vec3 inWater{0.1f, 0.12f, 0.06f};
  const Vec3 away = inWater + Vec3{1.0f, 0.0f, 0.0f};
  float bodySpeed = 0.0f, fluidSpeed = 0.0f;
  double t = 0.0;
  auto run = [&](Vec3 p, double seconds) {
    for (double until = t + seconds; t < until - 1e-9;) {
      t += kFrame;
      hand.pose.position = p;
      hand.time = t;
      ASSERT_TRUE(rig.Advance(t, {HandInput{}, hand}).ok());
      bodySpeed = std::max(bodySpeed, Length(rig.solver->BodyVelocity(0)));
      const sim::HostFluid f = test::DownloadFluid(*rig.solver);
      ASSERT_EQ(test::FirstNonFinite(f), "") << "at t = " << t;
      fluidSpeed = std::max(fluidSpeed, MaxSpeed(f));
    }
  };
  // Starts withdrawn above the tank (hand not yet seen): its first tracked frame is a re-entry.
  run(inWater, 0.4);
  EXPECT_EQ(rig.paddles->State(0).teleports, 1);
  EXPECT_EQ(rig.paddles->State(0).mode, PaddleMode::kFollowing);
  EXPECT_NEAR(Length(rig.solver->BodyPose(0).position - inWater), 0.0f, 1e-4f);
  run(away, 0.1);  // the jump: a teleport, the paddle glides towards it
  EXPECT_EQ(rig.paddles->State(0).teleports, 2);
  EXPECT_EQ(rig.paddles->State(0).mode, PaddleMode::kReentering);
  run(inWater, 0.3);  // and back (still gliding, so not a new teleport), then following again
  EXPECT_EQ(rig.paddles->State(0).mode, PaddleMode::kFollowing);
  EXPECT_NEAR(Length(rig.solver->BodyPose(0).position - inWater), 0.0f, 1e-4f);
  // The paddle never moved faster than the re-entry speed (1 m/s; a 1 m jump in one 90 Hz frame would be
  // 90 m/s), and the water stays below what a wall moving at that speed can give it: twice the wall's
  // speed (a particle reflected off it) plus the free-fall speed of the water's depth, sqrt(2 g 0.1 m) =
  // 1.4 m/s, so 3.4 m/s. (The splash's peak is chaotic: 2.9-3.0 m/s, by optimisation level.)
  EXPECT_LE(bodySpeed, limits.reentrySpeed * 1.001f);
  EXPECT_LT(fluidSpeed, 2.0f * limits.reentrySpeed + std::sqrt(2.0f * 9.81f * 0.1f));
  std::printf("teleports: paddle at most %.3f m/s, water at most %.3f m/s\n", bodySpeed, fluidSpeed);
}

// ---- tracking loss ----------------------------------------------------------------------------------

TEST(PaddleFluid, TrackingLossHoldsThenWithdraws) {
  // Coarser and softer (2 cm, sound speed 12 m/s) to keep 2.3 simulated seconds to a few seconds.
  sim::SceneSetup scene = SmallTank(0.02f, 20000.0f);
  const Vec3 a{0.08f, 0.12f, 0.06f}, b{0.16f, 0.12f, 0.06f};
  const double lost = 0.3;
  // Stirring until 0.3 s, then lost for 2 s.
  PaddleDesc d = Scripted({Key(0.0, a), Key(0.15, b), Key(lost, a), Key(lost + 1e-3, a, false), Key(lost + 2.0, a, false)});
  Rig rig = MakeRig(scene, {d});
  ASSERT_TRUE(rig.solver);
  const PaddleLimits& limits = rig.paddles->Desc(0).limits;
  double t = 0.0;
  Vec3 lastTracked{};
  float fluidSpeed = 0.0f;
  bool held = true;
  while (t < lost + 2.0 - 1e-9) {
    t += kFrame;
    ASSERT_TRUE(rig.Advance(t).ok());
    const Vec3 p = rig.solver->BodyPose(0).position;
    const sim::HostFluid f = test::DownloadFluid(*rig.solver);
    ASSERT_EQ(test::FirstNonFinite(f), "") << "at t = " << t;
    fluidSpeed = std::max(fluidSpeed, MaxSpeed(f));
    if (t <= lost + 1e-3) lastTracked = p;
    if (t > lost + 1e-3 && t < lost + limits.holdTime - kFrame) {
      held = held && p.x == lastTracked.x && p.y == lastTracked.y && p.z == lastTracked.z;
      EXPECT_EQ(rig.paddles->State(0).mode, PaddleMode::kHolding) << "t = " << t;
    }
  }
  EXPECT_TRUE(held) << "the paddle moved during the hold";
  EXPECT_EQ(rig.paddles->State(0).mode, PaddleMode::kWithdrawing);
  // Out of the water: every boundary particle of the paddle above the tank's top.
  std::vector<Vec4> pos, vel;
  rig.solver->DownloadBodies(&pos, &vel);
  float lowest = 1e9f;
  for (const Vec4& x : pos) lowest = std::min(lowest, x.y);
  EXPECT_GT(lowest, scene.tank.max.y);
  EXPECT_NEAR(rig.solver->BodyPose(0).position.x, lastTracked.x, 1e-6f) << "withdrawal is straight up";
  EXPECT_LT(fluidSpeed, 3.0f);
  EXPECT_NEAR(rig.solver->LastBodyLoad(0).force.y, 0.0f, 1e-6f) << "out of the water, no force";
}

// ---- determinism ------------------------------------------------------------------------------------

TEST(PaddleFluid, ScriptedTrajectoryReplaysBitwise) {
  test::TempDir dir("trajectory");
  // A figure of stirring written as a file, replayed twice from the file.
  std::string csv = "# time, px, py, pz, qw, qx, qy, qz\ntime,px,py,pz,qw,qx,qy,qz\n";
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.02 * k, phi = 2.0 * 3.14159265 * k / 20.0;
    csv += Format("%.4f, %.5f, 0.12, %.5f, %.6f, 0, %.6f, 0\n", t, 0.15 + 0.06 * std::cos(phi), 0.06 + 0.02 * std::sin(phi),
                  std::cos(phi / 2), std::sin(phi / 2));
  }
  const std::string path = dir.Write("stir.csv", csv);
  auto replay = [&](sim::HostFluid* out, std::vector<sim::BodyLoad>* loads) {
    PaddleDesc d;
    d.shapes = Blade();
    ASSERT_TRUE(Trajectory::Load(path, &d.trajectory).ok());
    ASSERT_EQ(d.trajectory.Keys().size(), 21u);
    Rig rig = MakeRig(SmallTank(0.02f, 20000.0f), {d});
    ASSERT_TRUE(rig.solver);
    for (double t = kFrame; t < 0.4; t += kFrame) {
      ASSERT_TRUE(rig.Advance(t).ok());
      loads->push_back(rig.solver->LastBodyLoad(0));
    }
    rig.solver->Download(out);
  };
  sim::HostFluid one, two;
  std::vector<sim::BodyLoad> loadsOne, loadsTwo;
  replay(&one, &loadsOne);
  replay(&two, &loadsTwo);
  ASSERT_EQ(one.size(), two.size());
  ASSERT_GT(one.size(), 0u);
  EXPECT_GT(MaxSpeed(one), 0.1f) << "the paddle should have stirred the water";
  EXPECT_EQ(0, std::memcmp(one.position.data(), two.position.data(), one.size() * sizeof(Vec4)));
  EXPECT_EQ(0, std::memcmp(one.velocity.data(), two.velocity.data(), one.size() * sizeof(Vec4)));
  EXPECT_EQ(one.id, two.id);
  ASSERT_EQ(loadsOne.size(), loadsTwo.size());
  EXPECT_EQ(0, std::memcmp(loadsOne.data(), loadsTwo.data(), loadsOne.size() * sizeof(sim::BodyLoad)));
}

}  // namespace
}  // namespace sphxr::interaction

namespace sphxr::interaction {
namespace {

// ---- two-way: the fluid's force on a paddle held still is Archimedes' buoyancy -----------------------

constexpr double kCubeBuoyancy = 1000.0 * 9.81 * 0.05 * 0.05 * 0.05;  // rho g V of the 5 cm cube: 1.23 N

/// A 5 cm cube held 6 cm deep in water at rest (12 cm deep, 1 cm spacing) under `method`, and the
/// fluid's force on it: summed from the boundary particles' reactions, the mean over 0.3-0.6 s. Then
/// the truth, independent of the solver: rho g V upwards, within `band` of it, and nothing sideways.
void HeldCubeFeelsArchimedesBuoyancy(sim::SolverMethod method, double band) {
  sim::SceneSetup scene = test::TankScene({0, 0, 0}, {0.12f, 0.16f, 0.12f}, 0.01f);
  scene.method = method;
  scene.params.stiffness = 20000.0f;  // (WCSPH's; PBF and DFSPH ignore the stiffness)
  scene.params.viscosity = 0.3f;
  scene.params.boundaryViscosity = 0.3f;
  scene.fluid.push_back(test::Block({0, 0, 0}, {0.12f, 0.12f, 0.12f}));
  PaddleDesc d;
  d.name = "cube";
  sim::ShapePrimitive cube;
  cube.kind = sim::ShapePrimitive::Kind::kBox;
  cube.b = Vec3{0.025f, 0.025f, 0.025f};
  d.shapes = {cube};
  const Vec3 centre{0.06f, 0.06f, 0.06f};
  ASSERT_TRUE(Trajectory::FromKeys({Key(0.0, centre)}, &d.trajectory).ok());
  Rig rig = MakeRig(scene, {d});
  ASSERT_TRUE(rig.solver);
  double sum[3] = {0, 0, 0};
  int samples = 0;
  for (double t = kFrame; t < 0.6; t += kFrame) {
    ASSERT_TRUE(rig.Advance(t).ok());
    if (t < 0.3) continue;  // the lattice settles first
    const sim::BodyLoad& load = rig.solver->LastBodyLoad(0);
    sum[0] += load.force.x, sum[1] += load.force.y, sum[2] += load.force.z;
    ++samples;
  }
  ASSERT_EQ(test::FirstNonFinite(test::DownloadFluid(*rig.solver)), "");
  const double buoyancy = kCubeBuoyancy;
  const double fx = sum[0] / samples, fy = sum[1] / samples, fz = sum[2] / samples;
  std::printf("held cube (%s): mean force [%.4f %.4f %.4f] N, Archimedes %.4f N (%+.1f %%), %d fluid particles\n",
              sim::SolverMethodName(method), fx, fy, fz, buoyancy, 100.0 * (fy / buoyancy - 1.0),
              rig.solver->FluidCount());
  EXPECT_GT(fy, 0.0);
  EXPECT_NEAR(fy, buoyancy, band * buoyancy);
  EXPECT_LT(std::abs(fx), 0.05 * buoyancy);
  EXPECT_LT(std::abs(fz), 0.05 * buoyancy);
  // The haptic amplitude is the filtered force over the full-scale force.
  const PaddleState& st = rig.paddles->State(0);
  EXPECT_NEAR(st.haptic, std::min(1.0f, Length(st.force) / d.haptics.fullScaleForce), 1e-6f);
}

TEST(PaddleFluid, HeldStillInWaterFeelsArchimedesBuoyancy) {
  // Measured: +21 % at 1 cm spacing (+24 % at 0.8 cm, so it does not shrink with the spacing over this
  // range). Partly explained: the equilibrium pressure gradient is up to 6 % steeper than rho0 g in this
  // solver (docs/dev/physics.md; the kernel gradient is not normalised on the lattice). The rest is not:
  // mirroring the pressure alone (p_b = p_i, no neighbour average) gives the same figure, so it is not
  // the wall-pressure extrapolation; the convex edges and corners, which the flat-wall correction leaves
  // light, are a suspect. We assert the sign and the magnitude within 30 % (docs/dev/paddles.md).
  HeldCubeFeelsArchimedesBuoyancy(sim::SolverMethod::kWcsph, 0.30);
}

TEST(PaddleFluid, HeldStillInPbfWaterFeelsArchimedesBuoyancy) {
  // Under PBF the force is the impulse of the constraint corrections the cube's boundary particles
  // cause, read through the pressure estimate (solvers/pbf/pbf_stages.h). The same truth in WCSPH's band.
  HeldCubeFeelsArchimedesBuoyancy(sim::SolverMethod::kPbf, 0.30);
}

}  // namespace
}  // namespace sphxr::interaction

namespace sphxr::interaction {
namespace {

// ---- reuse: particles near a moving paddle always compute -------------------------------------------

TEST(PaddleFluid, ParticlesNearAPaddleStayActiveUnderReuse) {
  // Reuse set to make every particle it classifies inactive (threshold far above any activity): only the
  // paddle's hook (ActivityStage: a moving boundary in the 27 cells) keeps particles active.
  sim::SceneSetup scene = SmallTank(0.015f, 20000.0f);
  scene.reuse.enabled = true;
  scene.reuse.threshold = 1e9f;
  scene.reuse.idle = 5;
  const Vec3 a{0.08f, 0.12f, 0.06f}, b{0.2f, 0.12f, 0.06f};
  Rig rig = MakeRig(scene, {Scripted({Key(0.0, a), Key(0.3, b)})});
  ASSERT_TRUE(rig.solver);
  const float reach = 0.7f * rig.solver->SupportRadius();  // a step moves a particle less than 0.2 support
  int checked = 0, idleFar = 0;
  for (double t = kFrame; t < 0.2; t += kFrame) {
    ASSERT_TRUE(rig.Advance(t).ok());
    const sim::HostFluid f = test::DownloadFluid(*rig.solver);
    std::vector<Vec4> body, vel;
    rig.solver->DownloadBodies(&body, &vel);
    for (size_t i = 0; i < f.size(); ++i) {
      float nearest = 1e9f;
      for (const Vec4& x : body) nearest = std::min(nearest, Length(Xyz(x) - Xyz(f.position[i])));
      if (nearest < reach) {
        ++checked;
        // Active is IC < 0: -1, or below -1 when the force stage's acceleration guard flagged it (docs/design/impulse_hold.md).
        EXPECT_LT(f.idle[i], 0) << "particle " << f.id[i] << " " << nearest << " m from the paddle reused at t = " << t;
      } else if (f.idle[i] >= 0) {
        ++idleFar;
      }
    }
  }
  EXPECT_GT(checked, 100) << "no particle came near the paddle: the test would prove nothing";
  EXPECT_GT(idleFar, 0) << "reuse never skipped a particle: the settings do not exercise the hook";
  EXPECT_EQ(test::FirstNonFinite(test::DownloadFluid(*rig.solver)), "");
}

// A paddle far larger than the tank is refused before it is sampled (a capsule of radius 100 m would
// take 8.9 GB).
TEST(PaddleSystem, AHugePaddleIsRefusedBeforeItIsSampled) {
  const sim::SceneSetup scene = test::SmallDamBreak(0.01f);
  for (const sim::ShapePrimitive& shape :
       {sim::ShapePrimitive{sim::ShapePrimitive::Kind::kCapsule, {0, 0, 0}, {0, 0, 0}, 100.0f},
        sim::ShapePrimitive{sim::ShapePrimitive::Kind::kBox, {0, 0, 0}, {6e9f, 0.01f, 0.01f}, 0.0f}}) {
    interaction::PaddleDesc d;
    d.name = "big";
    d.holder = interaction::Holder::kLeftHand;
    d.shapes = {shape};
    std::unique_ptr<interaction::PaddleSystem> system;
    Status s;
    const double seconds = test::Seconds([&] { s = interaction::PaddleSystem::Create({d}, scene, &system); });
    test::ExpectBriefRefusal(s, "more than the tank's");
    EXPECT_LT(seconds, 1.0);
  }
}

}  // namespace
}  // namespace sphxr::interaction
