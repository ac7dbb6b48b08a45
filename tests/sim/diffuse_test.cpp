// Diffuse particles (spray, foam, bubbles; Ihmsen et al. 2012; sim/src/stages/diffuse.h, diffuse_pool.h).
// The truths: still water traps no air and breaks no wave (none spawn); a stirred tank does; the
// paper's classification by fluid neighbours on a hand-made neighbourhood and its motion rules (a bubble
// rises, spray falls); the pool's capacity and its order (the oldest retired first); bit-identity across
// thread counts, against the host reference of the CUDA orchestration, and of the water itself with the
// diffuse particles on or off (they never act on it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "backend.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/app/state_file.h"
#include "sphxr/sim/diffuse.h"
#include "stages/diffuse.h"
#include "support.h"

namespace sphxr::sim {
namespace {

bool SameBits(const void* a, const void* b, size_t n) { return std::memcmp(a, b, n) == 0; }

bool SamePool(const HostDiffuse& a, const HostDiffuse& b) {
  return a.count == b.count && SameBits(a.position.data(), b.position.data(), a.position.size() * sizeof(Vec4)) &&
         SameBits(a.velocity.data(), b.velocity.data(), a.velocity.size() * sizeof(Vec4));
}

app::SceneFile LoadOrFail(const char* name) {
  app::SceneFile scene;
  const Status s = app::LoadScene(std::string(SPHXR_SCENES_DIR "/") + name, &scene);
  EXPECT_TRUE(s.ok()) << s.message();
  return scene;
}

/// The diffuse keys of `from` (every solver.diffuse* parameter) into `to`.
void CopyDiffuseKeys(const SolverParams& from, SolverParams* to) {
  for (const ParamInfo& p : SolverParamInfos()) {
    if (std::string(p.key).rfind("diffuse", 0) == 0) to->*p.member = from.*p.member;
  }
}

/// stir.json, the scene the diffuse particles are shown in, at 2 cm (1,700 particles) so that its paddle
/// stirs for half a second in about a second on one core; diffuse on or off.
std::unique_ptr<app::Simulation> Stir(bool diffuse, int threads = 1, Device device = Device::kCpu) {
  app::SceneFile scene = LoadOrFail("stir.json");
  EXPECT_GT(scene.setup.params.diffuse, 0.0f) << "stir.json is shown with its diffuse particles";
  scene.setup.params.spacing = 0.02f;
  scene.setup.params.diffuse = diffuse ? 1.0f : 0.0f;
  app::SimulationConfig config;
  config.solver.device = device;
  config.solver.threads = threads;
  std::unique_ptr<app::Simulation> sim;
  const Status s = app::Simulation::Create(app::SimSceneFromFile(scene), config, &sim);
  EXPECT_TRUE(s.ok()) << s.message();
  return sim;
}

bool StepSim(app::Simulation* sim, int steps) {
  for (int k = 0; k < steps; ++k) {
    if (Status s = sim->Step(); !s) {
      ADD_FAILURE() << "step " << k << ": " << s.message();
      return false;
    }
  }
  return true;
}

TEST(Diffuse, SettledStillWaterSpawnsNoneInOneSecond) {
  // tank_rest after its settle (the committed state the hydrostatic test observes), with the ranges of
  // the scene the particles are shown in (stir.json's, far below the paper's): a second of still water.
  app::SceneFile rest = LoadOrFail("tank_rest.json");
  CopyDiffuseKeys(LoadOrFail("stir.json").setup.params, &rest.setup.params);
  app::StateFile state;
  ASSERT_TRUE(app::ReadStateFile(SPHXR_TEST_DATA_DIR "/tank_rest_settled.state", &state).ok());
  EXPECT_EQ(state.diffuse.count, 0) << "a state file from before the diffuse particles loads with none";
  auto solver = test::CreateOrFail(rest.setup);
  ASSERT_TRUE(solver);
  ASSERT_TRUE(app::RestoreState(state, solver.get()).ok());
  const double end = solver->Time() + 1.0;
  int most = 0;
  float fastest = 0.0f;
  while (solver->Time() < end) {
    ASSERT_TRUE(solver->Step().ok());
    most = std::max(most, solver->DiffuseCount());
    fastest = std::max(fastest, solver->LastStep().maxSpeed);
  }
  EXPECT_EQ(most, 0) << "still water spawned diffuse particles";
  // The truth the test stands on: nothing in the tank reached the kinetic energy that spawns.
  EXPECT_LT(0.5f * fastest * fastest, rest.setup.params.diffuseEnergyMin);
}

TEST(Diffuse, TheStirredTankSpawnsAndKeepsThemInTheTank) {
  auto sim = Stir(true);
  ASSERT_TRUE(sim);
  const Solver& solver = sim->Solver();
  while (solver.Time() < 0.5) ASSERT_TRUE(StepSim(sim.get(), 1));
  HostDiffuse d;
  solver.DownloadDiffuse(&d);
  ASSERT_GT(d.count, 0) << "the paddle going round at 0.44 m/s spawned no foam or bubbles";
  EXPECT_EQ(solver.DiffuseCount(), d.count);
  const SceneSetup& s = solver.Scene();
  for (int i = 0; i < d.count; ++i) {
    const Vec4 p = d.position[i];
    EXPECT_TRUE(p.x >= s.tank.min.x && p.x <= s.tank.max.x && p.z >= s.tank.min.z && p.z <= s.tank.max.z &&
                p.y >= s.tank.min.y)
        << "diffuse particle " << i << " outside the tank";
    EXPECT_GT(p.w, 0.0f);
    EXPECT_LE(p.w, s.params.diffuseLifetime);
    const float kind = d.velocity[i].w;
    EXPECT_TRUE(kind == 0.0f || kind == 1.0f || kind == 2.0f) << kind;
  }
}

// ---- a hand-made neighbourhood: the classification and the motion rules ---------------------------

/// Fluid particles around a diffuse particle at the origin, on the GridView of a small box, sorted by
/// cell as the pool's grid holds them.
struct Neighbourhood {
  std::vector<Vec4> position, velocity;
  std::vector<uint32_t> start, end;
  GridView grid{};
  Physics ph{};

  Neighbourhood(int fluid, float support) {
    SceneSetup scene = test::TankScene({-0.1f, -0.1f, -0.1f}, {0.1f, 0.1f, 0.1f}, support / 2.0f);
    scene.params.diffuse = 1.0f;
    ph = MakePhysics(scene);
    // At half the support on a Fibonacci sphere: inside it, each one a neighbour of the origin.
    for (int k = 0; k < fluid; ++k) {
      const float y = 1.0f - 2.0f * (static_cast<float>(k) + 0.5f) / static_cast<float>(fluid);
      const float r = std::sqrt(1.0f - y * y), a = 2.39996323f * static_cast<float>(k);
      position.push_back(Vec4{0.5f * support * r * std::cos(a), 0.5f * support * y, 0.5f * support * r * std::sin(a), 0});
      velocity.push_back(Vec4{});
    }
    grid.origin = Vec3{-0.1f, -0.1f, -0.1f};
    grid.cellSize = support;
    grid.invCellSize = 1.0f / support;
    grid.nx = grid.ny = grid.nz = static_cast<int>(std::ceil(0.2f / support));
    const int cells = grid.nx * grid.ny * grid.nz;
    std::vector<uint32_t> cellOf(position.size());
    for (size_t i = 0; i < position.size(); ++i) {
      int cx, cy, cz;
      grid.CellOf(Xyz(position[i]), &cx, &cy, &cz);
      cellOf[i] = grid.Linear(cx, cy, cz);
    }
    std::vector<size_t> order(position.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cellOf[a] < cellOf[b]; });
    std::vector<Vec4> sorted;
    for (size_t i : order) sorted.push_back(position[i]);
    position = sorted;
    start.assign(cells, kEmptyCell);
    end.assign(cells, 0);
    for (size_t k = 0; k < order.size(); ++k) {
      const uint32_t c = cellOf[order[k]];
      if (start[c] == kEmptyCell) start[c] = static_cast<uint32_t>(k);
      end[c] = static_cast<uint32_t>(k + 1);
    }
    grid.fluidStart = start.data();
    grid.fluidEnd = end.data();
  }

  /// One advection step of a diffuse particle at `x` with velocity `v` (DiffuseAdvectStage).
  void Advect(Vec4* x, Vec4* v, float dt) {
    uint32_t alive = 0;
    DiffusePoolView pool{x, v, &alive, 1};
    DiffuseAdvectStage{grid, position.data(), velocity.data(), pool, ph, dt}(0);
  }
};

DiffuseKind KindWith(int fluid) {
  Neighbourhood n(fluid, 0.02f);
  Vec4 x{0, 0, 0, 1.0f}, v{};
  n.Advect(&x, &v, 1e-3f);
  return DiffuseKindOf(v);
}

TEST(Diffuse, FewFluidNeighboursIsSprayManyABubbleBetweenFoam) {
  // The paper's bounds (fewer than 6: spray, more than 20: a bubble) are the registry's defaults.
  EXPECT_EQ(KindWith(3), DiffuseKind::kSpray);
  EXPECT_EQ(KindWith(12), DiffuseKind::kFoam);
  EXPECT_EQ(KindWith(25), DiffuseKind::kBubble);
  EXPECT_EQ(KindWith(5), DiffuseKind::kSpray);
  EXPECT_EQ(KindWith(6), DiffuseKind::kFoam);
  EXPECT_EQ(KindWith(20), DiffuseKind::kFoam);
  EXPECT_EQ(KindWith(21), DiffuseKind::kBubble);
}

TEST(Diffuse, ABubbleRisesSprayFallsFoamRidesTheWaterAndAges) {
  const float dt = 1e-3f;
  {  // a bubble in water at rest: buoyancy k_b g up, drag toward the water's zero velocity
    Neighbourhood n(25, 0.02f);
    Vec4 x{0, 0, 0, 1.0f}, v{};
    n.Advect(&x, &v, dt);
    const float kb = n.ph.diffuse.buoyancy;
    EXPECT_FLOAT_EQ(v.y, kb * 9.81f * dt) << "v = v - dt k_b g + k_d (0 - v) from rest";
    EXPECT_GT(x.y, 0.0f) << "the bubble rose";
    EXPECT_EQ(x.w, 1.0f) << "bubbles do not age";
  }
  {  // spray: ballistic
    Neighbourhood n(3, 0.02f);
    Vec4 x{0, 0, 0, 1.0f}, v{0.5f, 0, 0, 0};
    n.Advect(&x, &v, dt);
    EXPECT_FLOAT_EQ(v.y, -9.81f * dt);
    EXPECT_FLOAT_EQ(v.x, 0.5f);
    EXPECT_LT(x.y, 0.0f);
    EXPECT_EQ(x.w, 1.0f) << "spray does not age";
  }
  {  // foam: the water's averaged velocity, and its lifetime shrinks by dt
    Neighbourhood n(12, 0.02f);
    for (Vec4& u : n.velocity) u = Vec4{0.2f, 0.0f, -0.1f, 0.0f};
    Vec4 x{0, 0, 0, 1.0f}, v{};
    n.Advect(&x, &v, dt);
    EXPECT_FLOAT_EQ(v.x, 0.2f);
    EXPECT_FLOAT_EQ(v.z, -0.1f);
    EXPECT_FLOAT_EQ(x.x, 0.2f * dt);
    EXPECT_FLOAT_EQ(x.w, 1.0f - dt);
  }
}

TEST(Diffuse, PotentialClampsToTheUnitInterval) {  // [IAAT12 eq. 1]
  EXPECT_EQ(DiffusePotential(1.0f, 5.0f, 20.0f), 0.0f);
  EXPECT_EQ(DiffusePotential(5.0f, 5.0f, 20.0f), 0.0f);
  EXPECT_FLOAT_EQ(DiffusePotential(12.5f, 5.0f, 20.0f), 0.5f);
  EXPECT_EQ(DiffusePotential(20.0f, 5.0f, 20.0f), 1.0f);
  EXPECT_EQ(DiffusePotential(300.0f, 5.0f, 20.0f), 1.0f);
}

// ---- the pool -------------------------------------------------------------------------------------

/// A still block of water (the stir ranges) in which one particle moves fast: only it has the kinetic
/// energy to spawn, its spawns per step about I_k k_ta dt.
struct OneFastParticle {
  std::unique_ptr<Solver> solver;
  Physics ph{};
  explicit OneFastParticle(int capacity, float trappedAir) {
    SceneSetup scene = test::TankScene({0, 0, 0}, {0.2f, 0.2f, 0.2f}, 0.01f);
    scene.fluid.push_back(test::Block({0, 0, 0}, {0.2f, 0.1f, 0.2f}));
    CopyDiffuseKeys(LoadOrFail("stir.json").setup.params, &scene.params);
    scene.params.diffuseCapacity = static_cast<float>(capacity);
    scene.params.diffuseTrappedAir = trappedAir;
    solver = test::CreateOrFail(scene);
    if (!solver) return;
    HostFluid f;
    solver->Download(&f);
    size_t middle = 0;  // the particle nearest the block's centre
    for (size_t i = 0; i < f.size(); ++i) {
      auto d = [&](size_t k) { return Length(Xyz(f.position[k]) - Vec3{0.1f, 0.05f, 0.1f}); };
      if (d(i) < d(middle)) middle = i;
    }
    f.velocity[middle] = Vec4{0.0f, 2.0f, 0.0f, 0.0f};
    EXPECT_TRUE(solver->Upload(f).ok());
    ph = MakePhysics(scene);
  }
  Status Advance(int step, float dt) {
    ph.step = step;
    return solver->BackendForTests()->AdvancePostSteps(dt, ph);
  }
};

TEST(Diffuse, ThePoolNeverExceedsItsCapacity) {
  // About 0.8 x 2e6 x 1e-3 = 1,600 spawns per step into a pool of 40.
  OneFastParticle w(40, 2e6f);
  ASSERT_TRUE(w.solver);
  for (int step = 1; step <= 20; ++step) {
    ASSERT_TRUE(w.Advance(step, 1e-3f).ok());
    ASSERT_EQ(w.solver->DiffuseCount(), 40) << "step " << step;
  }
}

TEST(Diffuse, AFullPoolRetiresTheOldestFirst) {
  // 60 marked spray particles (lifetime 1000 + k: spray does not age, so the mark survives a step) in a
  // pool of 64, oldest first, high above the water; then one step spawns some tens.
  OneFastParticle w(64, 20000.0f);
  ASSERT_TRUE(w.solver);
  HostDiffuse marked;
  marked.resize(60);
  for (int k = 0; k < 60; ++k) {
    marked.position[k] = Vec4{0.02f + 0.002f * k, 0.19f, 0.1f, 1000.0f + k};
    marked.velocity[k] = Vec4{0, 0, 0, static_cast<float>(DiffuseKind::kSpray)};
  }
  ASSERT_TRUE(w.solver->RestoreDiffuse(marked).ok());
  ASSERT_EQ(w.solver->DiffuseCount(), 60);
  ASSERT_TRUE(w.Advance(1, 1e-3f).ok());
  HostDiffuse after;
  w.solver->DownloadDiffuse(&after);
  EXPECT_EQ(after.count, 64) << "the spawns filled the pool";
  int kept = 0;
  while (kept < after.count && after.position[kept].w >= 1000.0f) ++kept;
  ASSERT_GT(kept, 0) << "the step should spawn fewer than the pool holds (tune trapped_air)";
  ASSERT_LT(kept, 60) << "the step should spawn more than the 4 free slots (tune trapped_air)";
  for (int k = 0; k < kept; ++k) {
    EXPECT_EQ(after.position[k].w, 1000.0f + static_cast<float>(60 - kept + k))
        << "the survivors are the newest marked ones, in their order";
  }
  for (int k = kept; k < after.count; ++k) EXPECT_LT(after.position[k].w, 1000.0f) << "then this step's spawns";
}

// ---- bit-identity -----------------------------------------------------------------------------------

TEST(Diffuse, SameBitsAtEveryThreadCount) {
  HostDiffuse pools[2];
  for (int t = 0; t < 2; ++t) {
    auto sim = Stir(true, t + 1);
    ASSERT_TRUE(sim);
    ASSERT_TRUE(StepSim(sim.get(), 400));
    sim->Solver().DownloadDiffuse(&pools[t]);
  }
  ASSERT_GT(pools[0].count, 0);
  EXPECT_TRUE(SamePool(pools[0], pools[1])) << pools[0].count << " / " << pools[1].count << " particles";
}

TEST(Diffuse, CpuAgreesWithTheCpuReferenceBitForBit) {
  // The stirred tank's water at a step that spawned (after a quarter second), frozen, given to both
  // backends; then the diffuse stage alone for 30 steps on each (the same source and inputs; the
  // orchestration is what may differ).
  auto stir = Stir(true);
  ASSERT_TRUE(stir);
  for (int before = 0; stir->Solver().Time() < 0.25 || stir->Solver().DiffuseCount() <= before;) {
    before = stir->Solver().DiffuseCount();
    ASSERT_TRUE(StepSim(stir.get(), 1));
    ASSERT_LT(stir->Solver().Time(), 1.0) << "no step spawned between 0.25 and 1 s";
  }
  HostFluid fluid;
  stir->Solver().Download(&fluid);
  HostDiffuse start;
  stir->Solver().DownloadDiffuse(&start);
  ASSERT_GT(start.count, 0);
  SceneSetup scene = stir->Solver().Scene();
  scene.params.diffuseTrappedAir *= 100.0f;  // so that the frozen water spawns in most steps
  scene.params.diffuseWaveCrest *= 100.0f;
  HostDiffuse pools[2];
  const Device devices[2] = {Device::kCpu, Device::kCpuReference};
  for (int b = 0; b < 2; ++b) {
    SolverConfig config;
    config.device = devices[b];
    config.threads = 1;
    auto solver = test::CreateOrFail(scene, config);  // (its paddle stays where it starts: the stage does not see it)
    ASSERT_TRUE(solver);
    ASSERT_TRUE(solver->Upload(fluid).ok());
    ASSERT_TRUE(solver->RestoreDiffuse(start).ok());
    Physics ph = MakePhysics(scene);
    for (int step = 1; step <= 30; ++step) {
      ph.step = 1000 + step;
      ASSERT_TRUE(solver->BackendForTests()->AdvancePostSteps(1e-3f, ph).ok());
    }
    solver->DownloadDiffuse(&pools[b]);
  }
  ASSERT_GT(pools[0].count, start.count) << "the frozen water should go on spawning";
  EXPECT_TRUE(SamePool(pools[0], pools[1])) << pools[0].count << " / " << pools[1].count << " particles";
}

TEST(Diffuse, TheWaterIsTheSameBitForBitWithThemOnOrOff) {
  HostFluid fluid[2];
  for (int on = 0; on < 2; ++on) {
    auto sim = Stir(on == 1);
    ASSERT_TRUE(sim);
    ASSERT_TRUE(StepSim(sim.get(), 400));
    if (on == 1) EXPECT_GT(sim->Solver().DiffuseCount(), 0) << "the comparison needs diffuse particles";
    sim->Solver().Download(&fluid[on]);
  }
  ASSERT_EQ(fluid[0].size(), fluid[1].size());
#define SPHXR_SAME_FIELD(type, name) \
  EXPECT_TRUE(SameBits(fluid[0].name.data(), fluid[1].name.data(), fluid[0].name.size() * sizeof(type))) << #name;
  SPHXR_FLUID_FIELDS(SPHXR_SAME_FIELD)
#undef SPHXR_SAME_FIELD
}

}  // namespace
}  // namespace sphxr::sim
