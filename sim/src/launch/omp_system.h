#pragma once
// What the two backends on thrust's OpenMP system share in their traits (backend_impl.h): the vectors,
// the policies (the launch layer's with its temporaries kept, launch/temporaries.h), host memory for
// the temporaries, a sum on the host, the stage clock on the host's clock, and nothing to wait for.
// The CPU backend (backend_cpu.cpp) and cpu-reference (backend_cpu_reference.cpp) add their name, how
// they count, their launcher and their surface settings.
#include <thrust/reduce.h>
#include <thrust/system/omp/execution_policy.h>
#include <thrust/system/omp/vector.h>

#include <cstddef>
#include <new>

#include "launch/host_clock.h"
#include "sphxr/common/status.h"

namespace sphxr::sim {

struct OmpSystem {
  template <class T>
  using Vector = thrust::omp::vector<T>;
  static auto Policy() { return thrust::omp::par; }
  /// The launch layer's policy: thrust's OpenMP system with its temporaries kept (launch/temporaries.h).
  template <class Temporaries>
  static auto Policy(Temporaries& temporaries) {
    return thrust::omp::par(temporaries);
  }
  static void* AllocateBytes(size_t bytes) { return ::operator new(bytes); }
  static void FreeBytes(void* block) { ::operator delete(block); }
  template <class Temporaries, class It, class T>
  static void SumInto(Temporaries& temporaries, It first, int n, T* out) {
    *out = thrust::reduce(Policy(temporaries), first, first + n, T{});
  }
  template <class T>
  using StageClock = HostStageClock<T>;  // stage timings on the host's clock (launch/host_clock.h)
  static Status Sync(const char* /*stage*/) { return Status::Ok(); }  // thrust's OpenMP calls return when done
};

}  // namespace sphxr::sim
