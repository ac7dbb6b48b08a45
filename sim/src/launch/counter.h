#pragma once
// The launch layer's counter (sphxr/sim/launch_counts.h): one per backend, incremented where the
// backend launches, waits, allocates or copies back. Host-only bookkeeping; the counts are read between
// steps, never inside a stage.
#include "sphxr/sim/launch_counts.h"

namespace sphxr::sim {

class LaunchCounter {
 public:
  void Launch(int kernels = 1) { m_c.launches += kernels; }
  void Sync() { ++m_c.syncs; }
  void Allocation() { ++m_c.allocations; }
  void Download() { ++m_c.downloads; }
  /// A blocking read of a device value: one copy back, one wait.
  void ReadBack() {
    Download();
    Sync();
  }
  const LaunchCounts& Counts() const { return m_c; }

 private:
  LaunchCounts m_c;
};

}  // namespace sphxr::sim
