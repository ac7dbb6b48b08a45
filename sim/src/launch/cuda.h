#pragma once
// The CUDA backend's launch pieces (backend_cuda.cu; the twin of cpu/launcher.h for the CPU): its one
// stream, its raw allocation for the kept temporaries (launch/temporaries.h), and its stage clock from
// CUDA events. Compiled by nvcc only.
#include <cub/device/device_reduce.cuh>
#include <cuda_runtime.h>

#include <new>
#include <vector>

#include "sphxr/common/log.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {

/// The backend's one stream. A blocking stream: it keeps its order with the legacy default stream, on
/// which thrust's vectors resize and copy, so a vector's fill or a download never overtakes a kernel.
inline cudaStream_t CudaStream() {
  static const cudaStream_t stream = [] {
    cudaStream_t s = nullptr;
    if (cudaStreamCreate(&s) != cudaSuccess) {
      cudaGetLastError();
      return cudaStream_t{nullptr};  // the legacy default stream: ordered, if slower
    }
    return s;
  }();
  return stream;
}

/// cudaMalloc, failing as thrust's allocations fail (std::bad_alloc, caught by GuardBackend).
inline void* CudaAllocate(size_t bytes) {
  void* block = nullptr;
  if (cudaMalloc(&block, bytes) != cudaSuccess) {
    cudaGetLastError();
    throw std::bad_alloc();
  }
  return block;
}

/// The sum of [first, first + n) into `out` (device memory) on the stream: CUB's two-phase call, its
/// temporary storage from the kept temporaries (launch/temporaries.h), so a steady step allocates nothing
/// and nothing waits.
template <class Temporaries, class It, class T>
void CudaSumInto(Temporaries& temporaries, It first, int n, T* out) {
  size_t bytes = 0;
  cub::DeviceReduce::Sum(nullptr, bytes, first, out, n, CudaStream());
  char* storage = temporaries.allocate(static_cast<std::ptrdiff_t>(bytes));
  cub::DeviceReduce::Sum(storage, bytes, first, out, n, CudaStream());
  temporaries.deallocate(storage, bytes);  // stream-ordered: the next user of the block runs after this
}

/// A launch error since the last check, naming the stage, without waiting for the device (a kernel's
/// fault surfaces at the step's next wait, the read of its reduction). The error is sticky: the context
/// is lost, so the message tells the user to restart on another device.
inline Status CudaCheck(const char* stage) {
  const cudaError_t e = cudaPeekAtLastError();
  if (e == cudaSuccess) return Status::Ok();
  return Status::Error(Format("cuda backend: %s in the %s stage (%s); restart, or use --device cpu",
                              cudaGetErrorString(e), stage, cudaGetErrorName(e)));
}

/// Stage timings from events on the stream, only when the run asks for them: Start and each Lap record
/// an event; Finish, after the step's end, adds each stage's elapsed time. Nothing here waits inside the
/// step; Finish waits for the last event (the step's end has usually passed it already).
class CudaStageClock {
 public:
  CudaStageClock() = default;
  CudaStageClock(const CudaStageClock&) = delete;
  CudaStageClock& operator=(const CudaStageClock&) = delete;
  ~CudaStageClock() {
    for (cudaEvent_t e : m_events) cudaEventDestroy(e);
  }

  /// `stageSeconds`: where Finish adds the stages' times; nullptr: the run asked for none.
  void Start(double* stageSeconds) {
    m_seconds = stageSeconds;
    m_timing = stageSeconds != nullptr;
    m_laps.clear();
    m_used = 0;
    if (m_timing) m_begin = Record();
  }
  /// Ends `stage` (its time from the last Start, Lap or Restart) and checks for a launch error.
  Status Lap(Stage stage) {
    if (m_timing) {
      const size_t end = Record();
      m_laps.push_back(LapEvents{m_begin, end, stage});
      m_begin = end;  // the next stage starts here
    }
    return CudaCheck(StageName(stage));
  }
  /// The next stage's time starts here (after a hook's host work).
  void Restart() {
    if (m_timing) m_begin = Record();
  }
  /// Adds each lap's seconds to the stage times; returns whether it waited.
  bool Finish() {
    if (!m_timing || m_laps.empty()) return false;
    cudaEventSynchronize(m_events[m_laps.back().end]);
    for (const LapEvents& lap : m_laps) {
      float ms = 0.0f;
      if (cudaEventElapsedTime(&ms, m_events[lap.begin], m_events[lap.end]) == cudaSuccess) {
        m_seconds[static_cast<int>(lap.stage)] += 1e-3 * ms;
      }
    }
    return true;
  }

 private:
  struct LapEvents {
    size_t begin, end;
    Stage stage;
  };
  size_t Record() {
    if (m_used == m_events.size()) {
      cudaEvent_t e = nullptr;
      cudaEventCreate(&e);
      m_events.push_back(e);
    }
    cudaEventRecord(m_events[m_used], CudaStream());
    return m_used++;
  }

  bool m_timing = false;
  double* m_seconds = nullptr;
  size_t m_begin = 0;
  size_t m_used = 0;
  std::vector<cudaEvent_t> m_events;  // created as needed, kept for the backend's life
  std::vector<LapEvents> m_laps;
};

}  // namespace sphxr::sim
