#pragma once
// The WCSPH solver (Becker & Teschner 2007) on a Z-ordered uniform grid (Huang et al. 2013, §3.1),
// with boundary particles after Akinci et al. (2012). One source for the CPU (OpenMP) and CUDA
// backends: see sim/src/stages.h for the per-particle stages and sim/src/backend_impl.h for the step.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/params.h"

namespace sphxr::sim {

enum class Device { kAuto, kCpu, kCuda };
const char* DeviceName(Device device);
/// Parses "auto" | "cpu" | "cuda".
bool ParseDevice(const std::string& text, Device* out);
/// True when the CUDA backend was compiled into this binary.
bool CudaBackendCompiled();
/// Number of CUDA devices usable (0 without a driver or without the CUDA backend).
int CudaDeviceCount();

struct SolverConfig {
  Device device = Device::kAuto;
  int threads = 0;        // CPU backend: 0 = all cores
  bool validate = false;  // check every stage for non-finite values (slow)
};

/// Stages of one step, each timed.
enum class Stage : int { kCells, kSort, kGrid, kActivity, kDensity, kForces, kIntegrate, kCount };
const char* StageName(Stage stage);

struct StepInfo {
  double time = 0.0;             // s, simulated time after the step
  float dt = 0.0f;               // s, the step taken
  float maxSpeed = 0.0f;         // m/s
  float meanDensityError = 0.0f; // mean of max(0, rho/rho0 - 1) over fluid particles
  float maxDensityError = 0.0f;  // max of |rho/rho0 - 1| over fluid particles
  int32_t clamped = 0;           // fluid particles pushed back into the domain this step
  float activeFraction = 1.0f;   // fraction of fluid particles that computed density and forces (reuse)
};

struct Totals {
  int64_t steps = 0;
  int64_t clampedEvents = 0;     // sum of StepInfo::clamped
  int64_t dtClampedSteps = 0;    // steps where a fixed dt was clamped to the CFL limit
  std::array<double, static_cast<int>(Stage::kCount)> stageSeconds{};
  double stepSeconds = 0.0;      // wall time in Step()
};

class Backend;

class Solver {
 public:
  /// Validates the scene, samples particles, and sets up the chosen backend. On error `*out` stays
  /// empty and the status says what to change.
  static Status Create(const SceneSetup& scene, const SolverConfig& config, std::unique_ptr<Solver>* out);
  ~Solver();

  /// Advances one time step. Fails only in validate mode (a non-finite value, named by stage and particle).
  Status Step();

  const StepInfo& LastStep() const { return m_last; }
  const Totals& GetTotals() const { return m_totals; }
  double Time() const { return m_last.time; }
  Device ActiveDevice() const { return m_device; }
  int FluidCount() const;
  int BoundaryCount() const;
  const SceneSetup& Scene() const { return m_scene; }
  float ParticleMass() const;
  float SupportRadius() const { return m_scene.params.spacing * m_scene.params.supportFactor; }
  float SoundSpeed() const;
  /// Maximum stable step for the current state (CFL, force and viscosity conditions).
  float StableDt() const;

  /// Copies all fluid fields to the host (current sorted order; use `id` for identity).
  void Download(HostFluid* out) const;
  void DownloadBoundary(HostBoundary* out) const;
  /// Replaces the fluid state (tests, restarts). Sizes must match FluidCount().
  Status Upload(const HostFluid& fluid);
  /// Neighbour-grid view for tests: cell index of a point, and the particle ranges.
  struct GridInfo {
    Vec3 origin;
    float cellSize;
    int dims[3];
  };
  GridInfo Grid() const;
  /// Test access to the backend (tests include the private headers on purpose).
  Backend* BackendForTests() { return m_backend.get(); }

 private:
  Solver() = default;
  SceneSetup m_scene;
  SolverConfig m_config;
  Device m_device = Device::kCpu;
  std::unique_ptr<Backend> m_backend;
  StepInfo m_last;
  Totals m_totals;
  float m_maxAccel = 0.0f;
  bool m_dtClampLogged = false;
};

}  // namespace sphxr::sim
