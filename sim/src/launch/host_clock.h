#pragma once
// Stage timings on the host's clock, for the backends whose work is done when its call returns (the
// CPU systems): the same calls as CudaStageClock (launch/cuda.h). Only when the run asks for timings.
#include <chrono>

#include "launch/device.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {

template <class Traits>
class HostStageClock {
 public:
  /// `stageSeconds`: where each Lap adds its stage's time; nullptr: the run asked for none.
  void Start(double* stageSeconds) {
    m_seconds = stageSeconds;
    m_laps = 0;
    Restart();
  }
  Status Lap(Stage stage) {
    if (!m_seconds) return Status::Ok();
    const auto now = std::chrono::steady_clock::now();
    m_seconds[static_cast<int>(stage)] += std::chrono::duration<double>(now - m_begin).count();
    m_begin = now;  // the next stage starts here
    ++m_laps;
    return Status::Ok();
  }
  void Restart() {
    if (m_seconds) m_begin = std::chrono::steady_clock::now();
  }
  /// Whether the step's end waits for its timings: on CUDA it waits for the last event, so
  /// cpu-reference, which counts what CUDA does, says so too.
  bool Finish() const { return Traits::kCountsAs == CountModel::kCuda && m_seconds && m_laps > 0; }

 private:
  double* m_seconds = nullptr;
  int m_laps = 0;
  std::chrono::steady_clock::time_point m_begin{};
};

}  // namespace sphxr::sim
