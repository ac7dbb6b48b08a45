// CPU backend: backend_impl.h on thrust's OpenMP system, with the CPU's launcher (SIMD stages).
#include <omp.h>

#include <chrono>
#include <thrust/system/omp/execution_policy.h>
#include <thrust/system/omp/vector.h>

#include "backend_impl.h"
#include "launch/omp_system.h"
#include "cpu/launcher.h"
#include "cpu/team.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/openmp_wait.h"

namespace sphxr::sim {
namespace {

struct OmpTraits : OmpSystem {
  static constexpr const char* kName = "cpu";
  static constexpr CountModel kCountsAs = CountModel::kCpu;  // a parallel loop or algorithm is one launch; nothing waits
  static constexpr bool kOnDevice = false;  // where the surface mesh lives
  static constexpr int kTraversalRun = 256;  // a descent per run of vertices: few threads, each stepping along the mesh
  static constexpr bool kSurfaceOverParticles = true;  // host memory: the particles' bounds cost no wait
  using Launcher = CpuLauncher<OmpTraits>;  // the SIMD density, force and wall-pressure stages (cpu/launcher.h)
};

/// The CPU backend: the team of each step chosen by TeamSizer (cpu/team.h) when the user left the
/// thread count to sphxr (--threads 0, the default); a given count is kept.
class CpuBackend final : public BackendImpl<OmpTraits> {
 public:
  explicit CpuBackend(int threads) : m_team(threads > 0 ? threads : omp_get_num_procs(), threads <= 0) {}

  Status Step(float dt, const Physics& physics, StepReduction* out, SolveReport* report, double* stageSeconds,
              const StageHook& hook) override {
    const int team = m_team.Threads();
    if (team != m_lastTeam) {
      if (m_lastTeam > 0) SPHXR_LOG_DEBUG("cpu backend: %d OpenMP threads from this step on", team);
      m_lastTeam = team;
    }
    omp_set_num_threads(team);  // (the calling thread's setting: the step's thread may be a worker's)
    const auto start = std::chrono::steady_clock::now();
    Status s = BackendImpl<OmpTraits>::Step(dt, physics, out, report, stageSeconds, hook);
    m_team.Record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return s;
  }

 private:
  TeamSizer m_team;
  int m_lastTeam = 0;
};

}  // namespace

std::unique_ptr<Backend> MakeCpuBackend(int threads) {
  // 0 = all cores, also after an earlier solver in this process asked for fewer.
  omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
  SPHXR_LOG_DEBUG("cpu backend: up to %d OpenMP threads (%s), waiting with %s",
                  threads > 0 ? threads : omp_get_num_procs(), threads > 0 ? "as asked" : "the team measured",
                  OpenMpWaitSetting());
  return std::make_unique<CpuBackend>(threads);
}

}  // namespace sphxr::sim
