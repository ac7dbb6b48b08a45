// CPU backend: the step of backend_impl.h on thrust's OpenMP system.
#include <omp.h>
#include <thrust/system/omp/execution_policy.h>
#include <thrust/system/omp/vector.h>

#include "backend_impl.h"
#include "cpu/stages.h"  // before the traits below name its stages

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
  static constexpr bool kSimdStages = true;  // density and forces in SIMD (cpu/density.h, cpu/forces.h)
  using BlockSet = sim::BlockSet;
  using DensityBlockStart = sim::DensityBlockStart;
  using DensityBlockStage = sim::DensityBlockStage;
  using ForceListStage = sim::ForceListStage;
  using WallPressureBlockStage = sim::WallPressureBlockStage;

  /// The SIMD stages' loop. thrust's OpenMP for_each gives each thread one equal slice; these stages'
  /// items cost what their neighbours and walls cost, and with reuse the compacted list puts the calm
  /// (skipped) water in one part of the index range, so one thread waited for the other at every stage
  /// (the spin in libgomp was 10 % of a step's samples with reuse off, 15 % with `balanced`). Guided
  /// chunks (libgomp: the remaining items over the thread count, so half the range first on 2 threads,
  /// then a quarter, ... down to `chunk` items) let the thread that finishes first take over the rest;
  /// they cannot help where the dearer work all lies in the first chunk, and measured 4-10 % faster
  /// than the equal slices (plain dynamic chunks: no gain). An item writes only its own results, so
  /// the schedule changes no number (docs/design/simd_stages.md).
  template <class F>
  static void ForEachGuided(int n, int chunk, const F& f) {
#pragma omp parallel for schedule(guided, chunk)
    for (int i = 0; i < n; ++i) f(i);
  }
};

}  // namespace

std::unique_ptr<Backend> MakeCpuBackend(int threads) {
  // 0 = all cores, also after an earlier solver in this process asked for fewer.
  omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
  return std::make_unique<BackendImpl<OmpTraits>>();
}

}  // namespace sphxr::sim
