// CPU backend: the step of backend_impl.h on thrust's OpenMP system.
#include <omp.h>
#include <thrust/system/omp/execution_policy.h>
#include <thrust/system/omp/vector.h>

#include "backend_impl.h"
#include "cpu_stages.h"  // before the traits below name its stages

namespace sphxr::sim {
namespace {

struct OmpTraits {
  template <class T>
  using Vector = thrust::omp::vector<T>;
  static auto Policy() { return thrust::omp::par; }
  static void Sync() {}
  static constexpr const char* kName = "cpu";
  static constexpr bool kOnDevice = false;  // where the surface mesh lives
  static constexpr int kTraversalRun = 256;  // a descent per run of vertices: few threads, each stepping along the mesh
  static constexpr bool kSimdStages = true;  // density and forces in SIMD (cpu_stages.h)
  using DensityBlockStart = sim::DensityBlockStart;
  using DensityBlockStage = sim::DensityBlockStage;
  using ForceListStage = sim::ForceListStage;
  using WallPressureBlockStage = sim::WallPressureBlockStage;
};

}  // namespace

std::unique_ptr<Backend> MakeCpuBackend(int threads) {
  // 0 = all cores, also after an earlier solver in this process asked for fewer.
  omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
  return std::make_unique<BackendImpl<OmpTraits>>();
}

}  // namespace sphxr::sim
