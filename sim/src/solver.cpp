// Solver: creating one (device choice, sampling, the backend's set-up), the time step (CFL, force and
// viscosity conditions) and the step with its statistics and validate hook. The rest of the class is in
// scene_check.cpp (what Create checks), restore.cpp, settle.cpp and bodies.cpp.
#include "sphxr/sim/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "backend.h"
#include "sampling.h"
#include "scene_check.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/openmp_wait.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {

Physics MakePhysics(const SceneSetup& scene) {
  const SolverParams& p = scene.params;
  Physics ph;
  const float support = p.spacing * p.supportFactor;
  ph.kernel = CubicSpline::Make(support);
  ph.mass = p.restDensity * p.spacing * p.spacing * p.spacing;
  ph.restDensity = p.restDensity;
  ph.invRestDensity = 1.0f / p.restDensity;
  ph.boundaryGamma = WallDensityCorrection(ph.kernel, p.spacing, scene.boundaryLayers);
  ph.boundaryGradScale = WallGradientCorrection(ph.kernel, p.spacing, scene.boundaryLayers) / ph.boundaryGamma;
  // The models the method supports (its row of the solver table); the scene check warns about the rest.
  const SolverInfo& method = SolverInfoOf(scene.method);
  ph.wallDensity = scene.wallPressure == SceneSetup::WallPressure::kWallDensity && method.wallDensity;
  ph.maxNeighbours = NeighbourCapacity(p.supportFactor);
  // Moving bodies are one-sheet shells (interaction::SamplePaddle): their own flat-wall corrections.
  ph.bodyGradScale = WallGradientCorrection(ph.kernel, p.spacing, 1) / WallDensityCorrection(ph.kernel, p.spacing, 1);
  ph.bodyClearance = 0.25f * p.spacing;
  const ReuseParams& r = scene.reuse;
  ph.continuityDensity = scene.density == DensityModel::kDeltaSph && method.deltaSph;
  // Reuse holds a summation density: an integrated density cannot skip steps.
  ph.reuseEnabled = r.enabled && method.reuse && !ph.continuityDensity;
  ph.reuseDelta1 = r.delta1;
  ph.reuseDelta2 = r.delta2;
  ph.reuseThreshold = r.threshold;
  ph.reuseIdle = r.idle;
  // P_pc: the Tait pressure at 1 % compression unless the scene sets it (our copy of the paper stops
  // before its parameter values); N_CPN: the rest lattice's particles per cell, (cell / dx)^3.
  const float pc = r.pressureScale > 0.0f ? r.pressureScale : p.stiffness * (std::pow(1.01f, p.exponent) - 1.0f);
  ph.reuseInvPressureScale = 1.0f / pc;
  ph.reuseCellCount = r.cellCount > 0.0f ? r.cellCount : p.supportFactor * p.supportFactor * p.supportFactor;
  ph.reuseSyncStep = true;  // Solver::Step sets it from the step's number
  ph.stiffness = p.stiffness;
  ph.exponent = p.exponent;
  ph.soundSpeed = std::sqrt(p.exponent * p.stiffness / p.restDensity);
  ph.smoothing = 0.5f * support;
  ph.alpha = p.viscosity;
  ph.gravity = scene.gravity;
  // Fluid particles are kept a quarter spacing inside the walls' boundary particles.
  const float inset = 0.25f * p.spacing;
  ph.domainMin = Vec3{scene.tank.min.x + inset, scene.tank.min.y + inset, scene.tank.min.z + inset};
  ph.domainMax = Vec3{scene.tank.max.x - inset, scene.tank.max.y - inset, scene.tank.max.z - inset};
  // Obstacles are sampled like the tank (a sheet half a spacing inside each face, fluid seeded half a
  // spacing outside): the same quarter-spacing inset, outward.
  ph.obstacleCount = static_cast<int>(std::min<size_t>(scene.obstacles.size(), kMaxObstacles));
  for (int k = 0; k < kMaxObstacles; ++k) {
    const bool used = k < ph.obstacleCount;
    const Aabb o = used ? scene.obstacles[k] : Aabb{};
    ph.obstacleMin[k] = used ? Vec3{o.min.x - inset, o.min.y - inset, o.min.z - inset} : Vec3{};
    ph.obstacleMax[k] = used ? Vec3{o.max.x + inset, o.max.y + inset, o.max.z + inset} : Vec3{};
  }
  ph.contactWidth = 0.1f * p.spacing;
  // Its potential at the clamp box stops a particle arriving at a quarter of the sound speed.
  ph.contactStrength =
      scene.wallContact && method.wallContact != ContactUse::kNone ? 3.0f * ph.soundSpeed * ph.soundSpeed / (32.0f * ph.contactWidth) : 0.0f;
  ph.contactBelowRestOnly = method.wallContact == ContactUse::kBelowRestDensity;
  ph.closedTop = !scene.openTop;
  ph.volume = ph.mass / p.restDensity;
  ph.densityTolerance = 0.01f * p.densityTolerance;  // % to a fraction
  ph.divergenceTolerance = 0.01f * p.divergenceTolerance;
  ph.minIterations = static_cast<int>(p.minIterations);
  ph.maxIterations = static_cast<int>(p.maxIterations);
  ph.minDivergenceIterations = static_cast<int>(p.minDivergenceIterations);
  ph.maxDivergenceIterations = static_cast<int>(p.maxDivergenceIterations);
  ph.pbfIterations = static_cast<int>(p.pbfIterations);
  // The constraint's scale D0 = sum_k |grad_k C_i|^2 of the rest lattice (1/m^2): epsilon and s_corr are
  // given relative to it, so that they mean the same at every spacing (MM13's 600 and 0.1 are in its own
  // units; s_corr enters beside lambda, whose scale is 1/D0).
  const float d0 = PbfRestGradientSum(ph.kernel, p.spacing, ph.volume);
  ph.pbfRelaxation = p.pbfRelaxation * d0;
  ph.pbfCorrK = p.pbfCorrK / d0;
  ph.pbfCorrN = static_cast<int>(p.pbfCorrN);
  ph.pbfInvCorrW = 1.0f / ph.kernel.W(p.pbfCorrDq * support);
  ph.pbfXsph = p.pbfXsph;
  ph.pbfVorticity = p.pbfVorticity;
  // The collision response keeps a particle its radius (half a spacing, where the sampling puts the
  // first layer) from a face: a quarter spacing beyond the clamp box's quarter-spacing inset.
  ph.pbfContact = 0.25f * p.spacing;
  ph.pbfMaxSpeed = p.pbfMaxSpeed;
  DiffuseConstants& d = ph.diffuse;
  d.enabled = p.diffuse > 0.0f;
  d.capacity = static_cast<int>(p.diffuseCapacity);
  d.trappedAir = p.diffuseTrappedAir;
  d.waveCrest = p.diffuseWaveCrest;
  d.trappedAirMin = p.diffuseTrappedAirMin;
  d.trappedAirMax = p.diffuseTrappedAirMax;
  d.waveCrestMin = p.diffuseWaveCrestMin;
  d.waveCrestMax = p.diffuseWaveCrestMax;
  d.energyMin = p.diffuseEnergyMin;
  d.energyMax = p.diffuseEnergyMax;
  d.lifetime = p.diffuseLifetime;
  d.buoyancy = p.diffuseBuoyancy;
  d.drag = p.diffuseDrag;
  d.sprayBelow = static_cast<int>(p.diffuseSprayBelow);
  d.bubbleAbove = static_cast<int>(p.diffuseBubbleAbove);
  d.radius = 0.5f * p.spacing;  // the fluid particle's radius
  ph.step = 0;  // Solver::Step sets it
  return ph;
}

std::string ClampSiteName(int site) {
  static const char* const kFaces[kTankFaces] = {"x- wall", "x+ wall", "floor", "top", "z- wall", "z+ wall"};
  SPHXR_ASSERT(site >= 0 && site < kClampSites);
  return site < kTankFaces ? kFaces[site] : Format("obstacles[%d]", site - kTankFaces);
}

void Solver::WarnIfWallsLeak() {
  // Judged once the run has taken 100,000 particle-steps (a few steps of a large scene, some tens of a
  // small one), then at most once per run.
  if (m_leakWarned || m_totals.particleSteps < 100000) return;
  const double rate = static_cast<double>(m_totals.clampedEvents) / static_cast<double>(m_totals.particleSteps);
  if (rate <= kLeakingClampRate) return;
  m_leakWarned = true;
  int worst = 0;
  for (int k = 1; k < kClampSites; ++k) {
    if (m_totals.clampedAt[k] > m_totals.clampedAt[worst]) worst = k;
  }
  const double share = static_cast<double>(m_totals.clampedAt[worst]) / static_cast<double>(m_totals.clampedEvents);
  SPHXR_LOG_WARN("the walls leak: %.3g clamps per 1,000 particle-steps by t = %.3g s (a safety net clamps under "
                 "%.2g), %.0f %% of them at the %s (logged once; docs/design/walls.md)",
                 1000.0 * rate, m_last.time, 1000.0 * kLeakingClampRate, 100.0 * share, ClampSiteName(worst).c_str());
}

const char* DeviceName(Device device) {
  switch (device) {
    case Device::kAuto: return "auto";
    case Device::kCpu: return "cpu";
    case Device::kCuda: return "cuda";
    case Device::kCpuReference: return "cpu-reference";
  }
  return "?";
}

bool ParseDevice(const std::string& text, Device* out) {
  if (text == "auto") *out = Device::kAuto;
  else if (text == "cpu") *out = Device::kCpu;
  else if (text == "cuda") *out = Device::kCuda;
  else if (text == "cpu-reference") *out = Device::kCpuReference;
  else return false;
  return true;
}

bool CudaBackendCompiled() { return CudaCompiled(); }
int CudaDeviceCount() { return CudaDevices(); }

const char* StageName(Stage stage) {
  switch (stage) {
    case Stage::kCells: return "cells";
    case Stage::kSort: return "sort";
    case Stage::kGrid: return "grid";
    case Stage::kActivity: return "activity";
    case Stage::kDensity: return "density";
    case Stage::kForces: return "forces";
    case Stage::kIntegrate: return "integrate";
    case Stage::kBodies: return "bodies";
    case Stage::kDivergence: return "divergence";
    case Stage::kPressure: return "pressure";
    case Stage::kProbes: return "probes";
    case Stage::kDiffuse: return "diffuse";
    default: return "?";
  }
}

Solver::~Solver() = default;

Status Solver::Create(const SceneSetup& scene, const SolverConfig& config, std::unique_ptr<Solver>* out) {
  out->reset();
  if (Status s = ValidateScene(scene); !s) return s;
  if (config.threads < 0 || config.threads > MaxSolverThreads()) {
    return Status::Error(Format("threads %d: must be from 0 (all cores) to %d (four per core here, at least 64)",
                                config.threads, MaxSolverThreads()));
  }

  std::unique_ptr<Solver> solver(new Solver());
  solver->m_scene = scene;
  solver->m_config = config;

  // Device choice: auto takes CUDA only when a device answers; explicit cuda without one is an error.
  Device device = config.device;
  if (device == Device::kAuto) {
    const int devices = CudaDevices();
    if (!CudaCompiled()) {
      SPHXR_LOG_INFO("device auto: CUDA backend not built, using the CPU backend");
      device = Device::kCpu;
    } else if (devices == 0) {
      SPHXR_LOG_INFO("device auto: no CUDA device found, using the CPU backend");
      device = Device::kCpu;
    } else {
      SPHXR_LOG_INFO("device auto: %d CUDA device(s) found, using the CUDA backend", devices);
      device = Device::kCuda;
    }
  }
  if (device == Device::kCuda) {
    std::string why;
    if (!CudaCompiled()) {
      MakeCudaBackend(&why);
      return Status::Error("--device cuda: " + why);
    }
    if (CudaDevices() == 0) {
      return Status::Error("--device cuda: no CUDA device available (no GPU or no driver); use --device cpu or auto");
    }
    solver->m_backend = MakeCudaBackend(&why);
  } else if (Status t = CheckThreadsCanStart(config.threads, Format("threads %d", config.threads)); !t) {
    return t;
  } else if (device == Device::kCpuReference) {
    solver->m_backend = MakeCpuReferenceBackend(config.threads);
  } else {
    solver->m_backend = MakeCpuBackend(config.threads);
  }
  solver->m_device = device;

  HostFluid fluid;
  std::vector<Vec4> positions;
  SampleFluid(scene, &positions);
  fluid.resize(positions.size());
  {
    size_t i = 0;
    // The scene without its blocks, copied once: a copy of the whole scene per block was quadratic
    // (97,336 blocks took 80 s here).
    SceneSetup one = scene;
    one.fluid.clear();
    for (const FluidBlock& block : scene.fluid) {
      // SampleFluid emits blocks in order; give each particle its block's initial velocity.
      one.fluid.assign(1, block);
      const int64_t n = SampleFluid(one, nullptr);
      // delta_sph integrates the density from here: a hydrostatic block starts at the Tait density of
      // each particle's depth below the block's top layer (plus half a spacing), as its lattice is
      // compressed; everything else at rho0.
      const bool hydrostatic = block.hydrostatic && scene.density == DensityModel::kDeltaSph;
      float top = -std::numeric_limits<float>::infinity();
      for (int64_t k = 0; k < n; ++k) top = std::max(top, positions[i + k].y);
      top += 0.5f * scene.params.spacing;
      for (int64_t k = 0; k < n; ++k, ++i) {
        fluid.position[i] = positions[i];
        fluid.velocity[i] = MakeVec4(block.velocity);
        fluid.id[i] = static_cast<uint32_t>(i);
        fluid.density[i] = scene.params.restDensity;
        if (hydrostatic) {
          const SolverParams& p = scene.params;
          const float head = p.restDensity * Length(scene.gravity) * (top - positions[i].y) / p.stiffness;
          fluid.density[i] = p.restDensity * std::pow(1.0f + head, 1.0f / p.exponent);
        }
        fluid.idle[i] = -1;  // every particle computes its first step
      }
    }
  }
  HostBoundary boundary;
  SampleBoundary(scene, &boundary.position, &boundary.viscosity);

  const Physics physics = MakePhysics(scene);
  if (physics.wallDensity) boundary.invReference = WallInverseReferences(scene, physics.kernel, boundary.position, 0.25f);
  if (Status s = solver->m_backend->Init(MakeGridShape(scene), physics, scene.method, fluid, boundary); !s) return s;
  if (!scene.bodies.empty()) solver->InitBodies(physics);
  WarnAboutSettings(scene, static_cast<int64_t>(positions.size()), physics.soundSpeed);
  LogCutBlocks(scene);
  *out = std::move(solver);
  return Status::Ok();
}

int Solver::FluidCount() const { return m_backend->FluidCount(); }
int Solver::BoundaryCount() const { return m_backend->BoundaryCount(); }
float Solver::ParticleMass() const { return MakePhysics(m_scene).mass; }
float Solver::SoundSpeed() const { return MakePhysics(m_scene).soundSpeed; }

float Solver::StableDt() const {
  const float speed = std::max(m_last.maxSpeed, MaxBodySpeed());
  const float accel = std::max(m_maxAccel, Length(m_scene.gravity));
  return SolverInfoOf(m_scene.method).stableDt(StableDtInput{m_scene, speed, accel});
}

Status Solver::Step() {
  const auto begin = std::chrono::steady_clock::now();
  float dt = StableDt();
  const float fixedDt = m_scene.params.fixedDt;
  if (fixedDt > 0.0f) {
    if (fixedDt <= dt) {
      dt = fixedDt;
    } else {
      ++m_totals.dtClampedSteps;
      if (!m_dtClampLogged) {
        m_dtClampLogged = true;
        SPHXR_LOG_WARN("fixed_dt = %g s is above the stability limit %g s (CFL %g, sound speed %.3g m/s) at t = %.4g s: "
                       "clamped to the limit (logged once)",
                       fixedDt, dt, m_scene.params.cfl, SoundSpeed(), m_last.time);
      }
    }
  }

  // A step that cannot advance the clock would loop forever (the force condition under an exploding
  // acceleration): say so instead.
  if (!(dt > 0.0f) || !std::isfinite(dt) || m_last.time + dt == m_last.time) {
    return Status::Error(Format("the time step collapsed to %g s at t = %.6g s (largest acceleration %g m/s^2): the "
                                "simulation has become unstable",
                                dt, m_last.time, m_maxAccel));
  }
  const int64_t stepNumber = m_stepBase + m_totals.steps + 1;
  StageHook hook;
  HostFluid host;
  if (m_config.validate) {
    m_backend->Download(&host);
    for (size_t i = 0; i < host.size(); ++i) {
      if (!Finite(Xyz(host.position[i])) || !Finite(Xyz(host.velocity[i]))) {
        const char* field = Finite(Xyz(host.position[i])) ? "velocity" : "position";
        return Status::Error(Format("validate: non-finite %s of particle %u at the start of step %lld", field,
                                    host.id[i], static_cast<long long>(stepNumber)));
      }
    }
    hook = [&](Stage stage) -> Status {
      m_backend->Download(&host);
      for (size_t i = 0; i < host.size(); ++i) {
        const char* bad = nullptr;
        if (!Finite(Xyz(host.position[i]))) bad = "position";
        else if (!Finite(Xyz(host.velocity[i]))) bad = "velocity";
        else if ((stage == Stage::kForces || stage == Stage::kIntegrate) && !Finite(Xyz(host.acceleration[i])))
          bad = "acceleration";
        else if (stage >= Stage::kDensity && !std::isfinite(host.density[i])) bad = "density";
        else if (stage >= Stage::kDensity && !std::isfinite(host.pressure[i])) bad = "pressure";
        if (bad) {
          return Status::Error(Format("validate: non-finite %s of particle %u after stage '%s' in step %lld", bad,
                                      host.id[i], StageName(stage), static_cast<long long>(stepNumber)));
        }
      }
      return Status::Ok();
    };
  }

  StepReduction red;
  Physics physics = MakePhysics(m_scene);
  physics.reuseSyncStep = stepNumber % (physics.reuseIdle + 1) == 0;
  physics.step = stepNumber;
  std::vector<BodyState> states;
  if (!m_bodies.empty()) {
    // Each body moves from its pose now to its interpolated pose at the end of the step; its particles
    // carry the rigid velocity that takes them there.
    const double end = m_last.time + dt;
    size_t firstShape = 0;
    for (BodyMotion& b : m_bodies) {
      const Pose to = BodyPoseAt(b, end);
      BodyState st{};
      st.position = b.pose.position;
      st.orientation = b.pose.orientation;
      st.velocity = (to.position - b.pose.position) * (1.0f / dt);
      st.angular = RotationVector(Mul(to.orientation, Conjugate(b.pose.orientation))) * (1.0f / dt);
      st.endPosition = to.position;
      st.endOrientation = to.orientation;
      st.boundRadius = b.boundRadius;
      st.firstShape = static_cast<int>(firstShape);
      st.shapeCount = static_cast<int>(b.shapes.size());
      firstShape += b.shapes.size();
      states.push_back(st);
    }
    m_backend->SetBodyStates(states);
  }
  if (Status s = m_backend->Step(dt, physics, &red, m_totals.stageSeconds.data(), hook); !s) return s;
  if (!m_bodies.empty()) {
    m_backend->BodyLoads(&m_bodyLoads);
    for (size_t k = 0; k < m_bodies.size(); ++k) {
      m_bodies[k].pose = Pose{states[k].endPosition, states[k].endOrientation};
      m_bodies[k].velocity = states[k].velocity;
      m_bodies[k].angular = states[k].angular;
    }
  }

  if (red.nonFinite > 0) {
    // Without --validate nothing else would notice: the step's maxima drop NaN, and a NaN particle
    // sits in the grid's last cell with no neighbours, exported and saved as NaN.
    return Status::Error(Format("%d fluid particles became non-finite (NaN or infinite position, velocity, acceleration "
                                "or density) in the step from t = %.6g s: the simulation has become unstable; rerun "
                                "with --validate to find the stage and particle, and lower solver.fixed_dt or raise "
                                "solver.stiffness",
                                red.nonFinite, m_last.time));
  }
  if (!m_probes.Empty()) ReadProbes(m_probes, m_probeDry, m_last.time, stepNumber - 1, &m_probeSample);
  m_last.time += dt;
  m_last.dt = dt;
  m_last.maxSpeed = std::sqrt(red.maxSpeed2);
  m_maxAccel = std::sqrt(red.maxAccel2);
  const int n = FluidCount();
  m_last.meanDensityError = n > 0 ? static_cast<float>(red.sumCompression / n) : 0.0f;
  m_last.maxDensityError = red.maxDensityError;
  m_last.clamped = red.clamped;
  m_last.activeFraction = n > 0 ? static_cast<float>(red.computed) / static_cast<float>(n) : 1.0f;
  m_totals.steps += 1;
  m_totals.clampedEvents += red.clamped;
  for (int k = 0; k < kClampSites; ++k) m_totals.clampedAt[k] += red.clampedAt[k];
  m_totals.particleSteps += n;
  WarnIfWallsLeak();
  m_last.pushedOut = red.pushed;
  m_totals.pushedOutEvents += red.pushed;
  m_last.densityIterations = red.densityIterations;
  m_last.divergenceIterations = red.divergenceIterations;
  m_last.solverDensityError = red.densityError;
  m_last.solverDivergenceError = red.divergenceError;
  m_totals.densityIterations += red.densityIterations;
  m_totals.divergenceIterations += red.divergenceIterations;
  if (SolverInfoOf(m_scene.method).iterationCap && red.densityIterations >= physics.maxIterations &&
      red.densityError > physics.densityTolerance) {
    // The solve stopped short: the water is more compressed than asked this step. Named with the error
    // reached, at most once per simulated second (a hard impact hits the cap for many steps in a row).
    ++m_totals.iterationCapSteps;
    if (m_iterationWarnTime < 0.0 || m_last.time >= m_iterationWarnTime + 1.0) {
      m_iterationWarnTime = m_last.time;
      SPHXR_LOG_WARN("%s: the density solve reached max_iterations = %d at t = %.4g s with a mean compression of "
                     "%.3g %% (density_tolerance %g %%; %lld such steps so far): raise solver.max_iterations or lower "
                     "solver.cfl",
                     SolverMethodName(m_scene.method), physics.maxIterations, m_last.time, 100.0 * red.densityError, 100.0 * physics.densityTolerance,
                     static_cast<long long>(m_totals.iterationCapSteps));
    }
  }
  m_totals.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return Status::Ok();
}

Solver::GridInfo Solver::Grid() const {
  const GridShape g = MakeGridShape(m_scene);
  return GridInfo{g.origin, g.cellSize, {g.nx, g.ny, g.nz}};
}

void Solver::SampleProbesNow() { m_backend->SampleProbesNow(MakePhysics(m_scene)); }

}  // namespace sphxr::sim
