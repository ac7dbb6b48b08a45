// Solver: creating one (the scene's check, the device and its backend, the start state's particles, the
// shared constants) and its small accessors. The step is solver_step.cpp; the rest of the class is in
// scene_check.cpp (what Create checks), restore.cpp, settle.cpp, bodies.cpp, probes.cpp and
// solver_surface.cpp.
#include "sphxr/sim/solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "backend.h"
#include "sampling.h"
#include "scene_check.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/openmp_wait.h"

namespace sphxr::sim {
namespace {

/// The device `config` asks for, and its backend: auto takes CUDA only when a device answers; an explicit
/// cuda without one is an error.
Status ChooseBackend(const SolverConfig& config, Device* device, std::unique_ptr<Backend>* backend) {
  *device = config.device;
  if (*device == Device::kAuto) {
    const int devices = CudaDevices();
    if (!CudaCompiled()) {
      SPHXR_LOG_INFO("device auto: CUDA backend not built, using the CPU backend");
      *device = Device::kCpu;
    } else if (devices == 0) {
      SPHXR_LOG_INFO("device auto: no CUDA device found, using the CPU backend");
      *device = Device::kCpu;
    } else {
      SPHXR_LOG_INFO("device auto: %d CUDA device(s) found, using the CUDA backend", devices);
      *device = Device::kCuda;
    }
  }
  if (*device == Device::kCuda) {
    std::string why;
    if (!CudaCompiled()) {
      MakeCudaBackend(&why);
      return Status::Error("--device cuda: " + why);
    }
    if (CudaDevices() == 0) {
      return Status::Error("--device cuda: no CUDA device available (no GPU or no driver); use --device cpu or auto");
    }
    *backend = MakeCudaBackend(&why);
  } else if (Status t = CheckThreadsCanStart(config.threads, Format("threads %d", config.threads)); !t) {
    return t;
  } else if (*device == Device::kCpuReference) {
    *backend = MakeCpuReferenceBackend(config.threads);
  } else {
    *backend = MakeCpuBackend(config.threads);
  }
  return Status::Ok();
}

/// The start state of the scene's fluid blocks: each particle with its block's velocity, at rest density
/// (or, for a hydrostatic block under delta_sph, the Tait density of its depth), every one computing its
/// first step.
void SampleStartFluid(const SceneSetup& scene, HostFluid* fluid) {
  std::vector<Vec4> positions;
  SampleFluid(scene, &positions);
  fluid->resize(positions.size());
  size_t i = 0;
  // The scene without its blocks, copied once: a copy of the whole scene per block is quadratic in the
  // block count.
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
      fluid->position[i] = positions[i];
      fluid->velocity[i] = MakeVec4(block.velocity);
      fluid->id[i] = static_cast<uint32_t>(i);
      fluid->density[i] = scene.params.restDensity;
      if (hydrostatic) {
        const SolverParams& p = scene.params;
        const float head = p.restDensity * Length(scene.gravity) * (top - positions[i].y) / p.stiffness;
        fluid->density[i] = p.restDensity * std::pow(1.0f + head, 1.0f / p.exponent);
      }
      fluid->idle[i] = -1;  // every particle computes its first step
    }
  }
}

}  // namespace

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

Solver::Solver() = default;
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
  if (Status s = ChooseBackend(config, &solver->m_device, &solver->m_backend); !s) return s;

  HostFluid fluid;
  SampleStartFluid(scene, &fluid);
  HostBoundary boundary;
  SampleBoundary(scene, &boundary.position, &boundary.viscosity);

  solver->m_physics = std::make_unique<Physics>(MakePhysics(scene));
  const Physics& physics = *solver->m_physics;
  if (physics.wallDensity) boundary.invReference = WallInverseReferences(scene, physics.kernel, boundary.position, 0.25f);
  if (Status s = solver->m_backend->Init(MakeGridShape(scene), scene, physics, fluid, boundary); !s) return s;
  if (!scene.bodies.empty()) solver->InitBodies(physics);
  WarnAboutSettings(scene, static_cast<int64_t>(fluid.size()), physics.soundSpeed);
  LogCutBlocks(scene);
  *out = std::move(solver);
  return Status::Ok();
}

void Solver::SceneChanged() {
  *m_physics = MakePhysics(m_scene);
  m_backend->InitSolver(m_scene, *m_physics);
}

int Solver::FluidCount() const { return m_backend->FluidCount(); }
LaunchCounts Solver::Counts() const { return m_backend->Counts(); }
int Solver::BoundaryCount() const { return m_backend->BoundaryCount(); }
float Solver::ParticleMass() const { return m_physics->mass; }
float Solver::SoundSpeed() const { return m_physics->soundSpeed; }

Solver::GridInfo Solver::Grid() const {
  const GridShape g = MakeGridShape(m_scene);
  return GridInfo{g.origin, g.cellSize, {g.nx, g.ny, g.nz}};
}

void Solver::SampleProbesNow() { m_backend->SampleProbesNow(*m_physics); }

}  // namespace sphxr::sim
