#pragma once
// What a backend asked of its device: kernel launches, host synchronisations, device allocations and
// the copies between host and device. The launch layer (sim/src/launch/) counts them on every backend;
// cpu-reference runs the CUDA backend's orchestration and counts each algorithm as the kernels it runs
// on CUDA, so its counts are what the CUDA backend does (docs/dev/backends.md, "What a step launches").
// Counts are cumulative since the backend was made; a frame's are the difference of two readings.
#include <cstdint>

namespace sphxr::sim {

struct LaunchCounts {
  int64_t launches = 0;     // kernels and memsets (a thrust or CUB algorithm counts the kernels it runs)
  int64_t syncs = 0;        // the host waited for the device (a blocking copy, a reduction's result, a device sync)
  int64_t allocations = 0;  // device memory allocated (cudaMalloc, or a vector or temporary grown)
  int64_t downloads = 0;    // device-to-host copies
  int64_t asked = 0;        // of those, the ones an output asked for (state, bodies' loads, probes, diffuse)
  int64_t uploads = 0;      // host-to-device copies

  /// Device-to-host copies that no output asked for (the step's own reads).
  int64_t UnaskedDownloads() const { return downloads - asked; }

  LaunchCounts& operator+=(const LaunchCounts& o) {
    launches += o.launches;
    syncs += o.syncs;
    allocations += o.allocations;
    downloads += o.downloads;
    asked += o.asked;
    uploads += o.uploads;
    return *this;
  }
  friend LaunchCounts operator-(LaunchCounts a, const LaunchCounts& b) {
    a.launches -= b.launches;
    a.syncs -= b.syncs;
    a.allocations -= b.allocations;
    a.downloads -= b.downloads;
    a.asked -= b.asked;
    a.uploads -= b.uploads;
    return a;
  }
  friend bool operator==(const LaunchCounts&, const LaunchCounts&) = default;
};

}  // namespace sphxr::sim
