#include "sphxr/sim/solver.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "backend.h"
#include "morton.h"
#include "sampling.h"
#include "sphxr/common/log.h"

namespace sphxr::sim {
namespace {

bool Finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
std::string Str(Vec3 v) { return Format("[%g, %g, %g]", v.x, v.y, v.z); }

Status ValidateBox(const Aabb& b, const std::string& key) {
  if (!Finite(b.min) || !Finite(b.max)) return Status::Error(key + ": min/max must be finite numbers");
  if (!(b.min.x < b.max.x && b.min.y < b.max.y && b.min.z < b.max.z)) {
    return Status::Error(key + ": min " + Str(b.min) + " must be below max " + Str(b.max) + " on every axis");
  }
  return Status::Ok();
}

bool Contains(const Aabb& outer, const Aabb& inner, float slack) {
  return inner.min.x >= outer.min.x - slack && inner.min.y >= outer.min.y - slack &&
         inner.min.z >= outer.min.z - slack && inner.max.x <= outer.max.x + slack &&
         inner.max.y <= outer.max.y + slack && inner.max.z <= outer.max.z + slack;
}

int64_t AvailableHostBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long pageSize = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || pageSize <= 0) return std::numeric_limits<int64_t>::max();
  return static_cast<int64_t>(pages) * pageSize * 3 / 4;  // leave a quarter to the OS and the renderer
}

Status ValidateScene(const SceneSetup& scene) {
  for (const ParamInfo& p : SolverParamInfos()) {
    const float v = scene.params.*p.member;
    if (!std::isfinite(v) || v < p.min || v > p.max) {
      return Status::Error(Format("solver.%s = %g is invalid: must be a number from %g to %g%s%s (%s)", p.key, v, p.min,
                                  p.max, p.unit[0] ? " " : "", p.unit, p.help));
    }
  }
  if (!std::isfinite(scene.floorViscosity) || scene.floorViscosity > 10.0f) {
    return Status::Error(Format("tank.floor_viscosity = %g is invalid: must be from 0 to 10", scene.floorViscosity));
  }
  {
    const ReuseParams& r = scene.reuse;
    const float values[] = {r.delta1, r.delta2, r.threshold, r.pressureScale, r.cellCount};
    const char* names[] = {"delta1", "delta2", "threshold", "pressure_scale", "cell_count"};
    for (int k = 0; k < 5; ++k) {
      if (!std::isfinite(values[k]) || values[k] < 0.0f || values[k] > 1e9f) {
        return Status::Error(Format("reuse.%s = %g is invalid: must be a number from 0 to 1e9", names[k], values[k]));
      }
    }
    if (r.idle < 0 || r.idle > 1000) {
      return Status::Error(Format("reuse.idle = %d is invalid: must be 0 to 1000 steps", r.idle));
    }
  }
  if (!Finite(scene.gravity)) return Status::Error("gravity must be three finite numbers");
  if (scene.boundaryLayers < 1 || scene.boundaryLayers > 4) {
    return Status::Error(Format("tank.boundary_layers = %d is invalid: must be 1 to 4", scene.boundaryLayers));
  }
  if (Status s = ValidateBox(scene.tank, "tank"); !s) return s;
  const float slack = 1e-5f * scene.params.spacing;
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    const std::string key = Format("fluid[%zu]", i);
    if (Status s = ValidateBox(scene.fluid[i].box, key); !s) return s;
    if (!Finite(scene.fluid[i].velocity)) return Status::Error(key + ".velocity must be three finite numbers");
    if (!Contains(scene.tank, scene.fluid[i].box, slack)) {
      return Status::Error(key + ": the block " + Str(scene.fluid[i].box.min) + " to " + Str(scene.fluid[i].box.max) +
                           " is not inside the tank " + Str(scene.tank.min) + " to " + Str(scene.tank.max));
    }
  }
  for (size_t i = 0; i < scene.obstacles.size(); ++i) {
    const std::string key = Format("obstacles[%zu]", i);
    if (Status s = ValidateBox(scene.obstacles[i], key); !s) return s;
    if (!Contains(scene.tank, scene.obstacles[i], slack)) {
      return Status::Error(key + ": the box is not inside the tank " + Str(scene.tank.min) + " to " +
                           Str(scene.tank.max));
    }
  }
  const float gamma = WallDensityCorrection(CubicSpline::Make(scene.params.spacing * scene.params.supportFactor),
                                            scene.params.spacing, scene.boundaryLayers);
  if (!(gamma > 0.0f)) {
    return Status::Error(Format("solver.support_factor = %g with %d boundary layer(s) leaves no room for the walls' "
                                "mass (the fluid lattice alone is over-dense): use a support factor of 2 or more",
                                scene.params.supportFactor, scene.boundaryLayers));
  }
  const GridShape grid = MakeGridShape(scene);
  const int dims[3] = {grid.nx, grid.ny, grid.nz};
  for (int a = 0; a < 3; ++a) {
    if (dims[a] > kMaxGridDim) {
      return Status::Error(Format("solver.spacing = %g makes the neighbour grid %d cells wide along %c; at most %d are "
                                  "supported: use a larger spacing or a smaller tank",
                                  scene.params.spacing, dims[a], "xyz"[a], kMaxGridDim));
    }
  }
  const ParticleCounts counts = CountParticles(scene);
  const int64_t need = EstimateMemoryBytes(counts);
  const int64_t have = AvailableHostBytes();
  if (need > have || counts.fluid > std::numeric_limits<int32_t>::max() / 2 ||
      counts.boundary > std::numeric_limits<int32_t>::max() / 2) {
    return Status::Error(Format("solver.spacing = %g gives %lld fluid and %lld boundary particles, needing about %.1f GiB; "
                                "this machine allows %.1f GiB: use a larger spacing",
                                scene.params.spacing, static_cast<long long>(counts.fluid),
                                static_cast<long long>(counts.boundary), need / 1073741824.0, have / 1073741824.0));
  }
  return Status::Ok();
}

// Settings that run but will not give usable water are named at start-up, once.
void WarnAboutSettings(const SceneSetup& scene, float soundSpeed) {
  const float g = Length(scene.gravity);
  float height = 0.0f;
  for (const FluidBlock& b : scene.fluid) height = std::max(height, b.box.max.y - scene.tank.min.y);
  const float vRef = std::sqrt(2.0f * g * height);
  if (vRef > 0.0f && soundSpeed < 5.0f * vRef) {
    const float needB = scene.params.restDensity * 100.0f * vRef * vRef / scene.params.exponent;
    SPHXR_LOG_WARN("sound speed %.3g m/s is only %.1fx the expected flow speed sqrt(2gH) = %.3g m/s: expect density "
                   "errors above 1%% (WCSPH wants 10x); solver.stiffness >= %.3g Pa would give that",
                   soundSpeed, soundSpeed / vRef, vRef, needB);
  }
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    const Aabb& b = scene.fluid[i].box;
    const float thin = std::min({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
    if (thin < 3.0f * scene.params.spacing) {
      SPHXR_LOG_WARN("fluid[%zu] is only %.1f spacings thick: too coarse to behave like water", i,
                     thin / scene.params.spacing);
    }
  }
}

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
  ph.maxNeighbours = NeighbourCapacity(p.supportFactor);
  const ReuseParams& r = scene.reuse;
  ph.reuseEnabled = r.enabled;
  ph.reuseDelta1 = r.delta1;
  ph.reuseDelta2 = r.delta2;
  ph.reuseThreshold = r.threshold;
  ph.reuseIdle = r.idle;
  // P_pc: the Tait pressure at 1 % compression unless the scene sets it (our copy of the paper stops
  // before its parameter values); N_CPN: the rest lattice's particles per cell, (cell / dx)^3.
  const float pc = r.pressureScale > 0.0f ? r.pressureScale : p.stiffness * (std::pow(1.01f, p.exponent) - 1.0f);
  ph.reuseInvPressureScale = 1.0f / pc;
  ph.reuseCellCount = r.cellCount > 0.0f ? r.cellCount : p.supportFactor * p.supportFactor * p.supportFactor;
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
  return ph;
}

struct FieldCheck {
  const char* name;
  bool (*finite)(const HostFluid&, size_t);
};

}  // namespace

const char* DeviceName(Device device) {
  switch (device) {
    case Device::kAuto: return "auto";
    case Device::kCpu: return "cpu";
    case Device::kCuda: return "cuda";
  }
  return "?";
}

bool ParseDevice(const std::string& text, Device* out) {
  if (text == "auto") *out = Device::kAuto;
  else if (text == "cpu") *out = Device::kCpu;
  else if (text == "cuda") *out = Device::kCuda;
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
    default: return "?";
  }
}

Solver::~Solver() = default;

Status Solver::Create(const SceneSetup& scene, const SolverConfig& config, std::unique_ptr<Solver>* out) {
  out->reset();
  if (Status s = ValidateScene(scene); !s) return s;
  if (config.threads < 0) return Status::Error(Format("threads = %d is invalid: must be 0 (all) or more", config.threads));

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
    for (const FluidBlock& block : scene.fluid) {
      // SampleFluid emits blocks in order; give each particle its block's initial velocity.
      SceneSetup one = scene;
      one.fluid = {block};
      const int64_t n = SampleFluid(one, nullptr);
      for (int64_t k = 0; k < n; ++k, ++i) {
        fluid.position[i] = positions[i];
        fluid.velocity[i] = MakeVec4(block.velocity);
        fluid.id[i] = static_cast<uint32_t>(i);
        fluid.density[i] = scene.params.restDensity;
        fluid.idle[i] = -1;  // every particle computes its first step
      }
    }
  }
  HostBoundary boundary;
  SampleBoundary(scene, &boundary.position, &boundary.viscosity);

  const Physics physics = MakePhysics(scene);
  if (Status s = solver->m_backend->Init(MakeGridShape(scene), physics, fluid, boundary); !s) return s;
  WarnAboutSettings(scene, physics.soundSpeed);
  *out = std::move(solver);
  return Status::Ok();
}

int Solver::FluidCount() const { return m_backend->FluidCount(); }
int Solver::BoundaryCount() const { return m_backend->BoundaryCount(); }
float Solver::ParticleMass() const { return MakePhysics(m_scene).mass; }
float Solver::SoundSpeed() const { return MakePhysics(m_scene).soundSpeed; }

float Solver::StableDt() const {
  const SolverParams& p = m_scene.params;
  const float h = 0.5f * p.spacing * p.supportFactor;
  const float c = std::sqrt(p.exponent * p.stiffness / p.restDensity);
  float dt = p.maxDt;
  // Acoustic CFL condition (Monaghan 1992; Becker & Teschner 2007, sec. 5).
  dt = std::min(dt, p.cfl * h / (c + m_last.maxSpeed));
  // Force condition: a particle must not move more than ~h/16 per step under its acceleration.
  const float accel = std::max(m_maxAccel, Length(m_scene.gravity));
  if (accel > 0.0f) dt = std::min(dt, 0.25f * std::sqrt(h / accel));
  // Viscous diffusion condition for the artificial viscosity (nu ~ alpha c h / 8).
  const float alpha = std::max({p.viscosity, p.boundaryViscosity, m_scene.floorViscosity});
  if (alpha > 0.0f) dt = std::min(dt, 0.5f * h / (alpha * c));
  return dt;
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

  const int64_t stepNumber = m_totals.steps + 1;
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
  const Physics physics = MakePhysics(m_scene);
  if (Status s = m_backend->Step(dt, physics, &red, m_totals.stageSeconds.data(), hook); !s) return s;

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
  m_totals.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return Status::Ok();
}

void Solver::Download(HostFluid* out) const { m_backend->Download(out); }
void Solver::DownloadBoundary(HostBoundary* out) const { m_backend->DownloadBoundary(out); }

Status Solver::Upload(const HostFluid& fluid) {
  if (static_cast<int>(fluid.size()) != FluidCount()) {
    return Status::Error(Format("Upload: %zu particles given, the solver has %d", fluid.size(), FluidCount()));
  }
#define SPHXR_CHECK_SIZE(type, name)                                                  \
  if (fluid.name.size() != fluid.size())                                              \
    return Status::Error("Upload: field '" #name "' has a different size than position");
  SPHXR_FLUID_FIELDS(SPHXR_CHECK_SIZE)
#undef SPHXR_CHECK_SIZE
  m_backend->Upload(fluid);
  return Status::Ok();
}

Solver::GridInfo Solver::Grid() const {
  const GridShape g = MakeGridShape(m_scene);
  return GridInfo{g.origin, g.cellSize, {g.nx, g.ny, g.nz}};
}

}  // namespace sphxr::sim
