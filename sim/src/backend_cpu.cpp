// CPU backend: backend_impl.h on thrust's OpenMP system, with the CPU's launcher (SIMD stages).
#include <omp.h>
#include <thrust/system/omp/execution_policy.h>
#include <thrust/system/omp/vector.h>

#include "backend_impl.h"
#include "cpu/launcher.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/openmp_wait.h"

namespace sphxr::sim {
namespace {

struct OmpTraits {
  template <class T>
  using Vector = thrust::omp::vector<T>;
  static auto Policy() { return thrust::omp::par; }
  static Status Sync(const char* /*stage*/) { return Status::Ok(); }  // thrust's OpenMP calls return when done
  static constexpr const char* kName = "cpu";
  static constexpr bool kOnDevice = false;  // where the surface mesh lives
  static constexpr int kTraversalRun = 256;  // a descent per run of vertices: few threads, each stepping along the mesh
  using Launcher = CpuLauncher<OmpTraits>;  // the SIMD density, force and wall-pressure stages (cpu/launcher.h)
};

}  // namespace

std::unique_ptr<Backend> MakeCpuBackend(int threads) {
  // 0 = all cores, also after an earlier solver in this process asked for fewer.
  omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
  SPHXR_LOG_DEBUG("cpu backend: %d OpenMP threads, waiting with %s", threads > 0 ? threads : omp_get_num_procs(),
                  OpenMpWaitSetting());
  return std::make_unique<BackendImpl<OmpTraits>>();
}

}  // namespace sphxr::sim
