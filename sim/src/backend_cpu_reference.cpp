// The CUDA backend's step on the host: backend_impl.h with backend_cuda.cu's launcher (launch/plain.h: a
// work item per particle over the full or compacted lists, the per-particle DensityStage and ForceStage,
// the per-cell WallPressureStage; a traversal work item per surface vertex) on thrust's OpenMP system.
// Without a GPU this is how every suite exercises the code the CUDA backend runs; the `cpu` backend's
// launcher (cpu/launcher.h) replaces density, forces and wall pressure by the SIMD forms and is held
// against this one step by step (tests/backend/agreement_test.cpp). Slow: that is fine.
#include <omp.h>
#include <thrust/system/omp/execution_policy.h>
#include <thrust/system/omp/vector.h>

#include "backend_impl.h"
#include "launch/omp_system.h"
#include "launch/plain.h"

namespace sphxr::sim {
namespace {

struct OmpReferenceTraits : OmpSystem {
  static constexpr const char* kName = "cpu-reference";
  static constexpr CountModel kCountsAs = CountModel::kCuda;  // counts what the CUDA backend launches (launch/kernels.h)
  static constexpr bool kOnDevice = false;   // the mesh is host memory (CUDA's is device memory: the only difference)
  static constexpr bool kSurfaceOverParticles = false;  // as CUDA: the lattice over the clamp box
  static constexpr int kTraversalRun = 1;    // as CUDA: one descent per vertex
  using Launcher = PlainLauncher<OmpReferenceTraits>;  // as CUDA: a work item per particle (launch/plain.h)
};

}  // namespace

std::unique_ptr<Backend> MakeCpuReferenceBackend(int threads) {
  omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
  return std::make_unique<BackendImpl<OmpReferenceTraits>>();
}

}  // namespace sphxr::sim
