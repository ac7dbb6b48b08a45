// CUDA backend: the same step of backend_impl.h on thrust's CUDA system (cub radix sort underneath).
#include <cuda_runtime.h>
#include <thrust/system/cuda/execution_policy.h>
#include <thrust/system/cuda/vector.h>

#include "backend_impl.h"
#include "launch/cuda.h"
#include "launch/plain.h"

namespace sphxr::sim {
namespace {

struct CudaTraits {
  template <class T>
  using Vector = thrust::cuda::vector<T>;
  static auto Policy() { return thrust::cuda::par; }
  /// The launch layer's policy (launch/device.h): no wait at an algorithm's end, on the backend's one
  /// stream, the temporaries kept between steps (launch/temporaries.h).
  template <class Temporaries>
  static auto Policy(Temporaries& temporaries) {
    return thrust::cuda::par_nosync(temporaries).on(CudaStream());
  }
  static void* AllocateBytes(size_t bytes) { return CudaAllocate(bytes); }
  static void FreeBytes(void* block) { cudaFree(block); }
  template <class Temporaries, class It, class T>
  static void SumInto(Temporaries& temporaries, It first, int n, T* out) {
    CudaSumInto(temporaries, first, n, out);
  }
  template <class T>
  using StageClock = CudaStageClock;  // stage timings from events on the stream (launch/cuda.h)
  /// Waits for the stage's kernels and reports the first error since the last check, naming the stage (a
  /// kernel's fault surfaces here, at the stage boundary; a Debug build also synchronises and checks
  /// after every launch: THRUST_DEBUG_SYNC, sim/CMakeLists.txt). An error here is sticky: the context
  /// is lost, so the message tells the user to restart on another device.
  static Status Sync(const char* stage) {
    cudaError_t e = cudaDeviceSynchronize();
    if (e == cudaSuccess) e = cudaGetLastError();
    if (e == cudaSuccess) return Status::Ok();
    return Status::Error(Format("cuda backend: %s in the %s stage (%s); restart, or use --device cpu",
                                cudaGetErrorString(e), stage, cudaGetErrorName(e)));
  }
  static constexpr const char* kName = "cuda";
  static constexpr CountModel kCountsAs = CountModel::kCuda;
  static constexpr bool kOnDevice = true;  // where the surface mesh lives
  static constexpr bool kSurfaceOverParticles = false;  // no read-back: the lattice over the clamp box
  static constexpr int kTraversalRun = 1;  // one descent per vertex: a thread each
  using Launcher = PlainLauncher<CudaTraits>;  // a thread per particle (launch/plain.h)
};

}  // namespace

std::unique_ptr<Backend> MakeCudaBackend(std::string* /*why*/) {
  return std::make_unique<BackendImpl<CudaTraits>>();
}

int CudaDevices() {
  int count = 0;
  // Without a driver this returns an error (cudart is linked statically, so the program still starts).
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();
    return 0;
  }
  return count;
}

bool CudaCompiled() { return true; }

}  // namespace sphxr::sim
