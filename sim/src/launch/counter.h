#pragma once
// The launch layer's counter (sphxr/sim/launch_counts.h): one per backend, incremented by the counted
// device operations (launch/device.h) where the backend launches, waits, allocates or copies. Host-only
// bookkeeping; the counts are read between steps, never inside a stage.
#include "sphxr/sim/launch_counts.h"

namespace sphxr::sim {

class LaunchCounter {
 public:
  void Launch(int kernels = 1) { m_c.launches += kernels; }
  void Sync() { ++m_c.syncs; }
  void Allocation() { ++m_c.allocations; }
  /// A device-to-host copy; `asked`: an output asked for it (a state download, the bodies' loads).
  void Download(bool asked = false) {
    ++m_c.downloads;
    if (asked) ++m_c.asked;
  }
  void Upload() { ++m_c.uploads; }
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
