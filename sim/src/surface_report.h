#pragma once
// Where the surface traversal leaves its report (DeviceWriteReport, surface_stages.h): memory the device
// writes and the host reads with a plain load, no copy and no wait. On the CUDA backend it is mapped
// pinned host memory (cudaHostAlloc with cudaHostAllocMapped; the kernel's stores cross the bus), on the
// host backends an ordinary struct. The host reads it a frame later, when the device has finished the
// write that filled it (the report's write number says whether it has).
#include <cstdint>

#if defined(__CUDACC__)
#include <cuda_runtime.h>
#endif

#include "sphxr/common/status.h"
#include "surface_stages.h"

namespace sphxr::sim {

template <bool kOnDevice>
class HostVisibleReport;

template <>
class HostVisibleReport<false> {
 public:
  Status Init() { return Status::Ok(); }
  DeviceWriteReport* Device() { return &m_report; }
  const volatile DeviceWriteReport* Host() const { return &m_report; }

 private:
  DeviceWriteReport m_report{};
};

#if defined(__CUDACC__)
template <>
class HostVisibleReport<true> {
 public:
  HostVisibleReport() = default;
  HostVisibleReport(const HostVisibleReport&) = delete;
  HostVisibleReport& operator=(const HostVisibleReport&) = delete;
  ~HostVisibleReport() {
    if (m_host) cudaFreeHost(m_host);
  }
  Status Init() {
    if (m_host) return Status::Ok();
    void* host = nullptr;
    if (cudaError_t e = cudaHostAlloc(&host, sizeof(DeviceWriteReport), cudaHostAllocMapped); e != cudaSuccess) {
      return Status::Error(Format("cuda backend: mapped host memory for the surface's report: %s", cudaGetErrorString(e)));
    }
    *static_cast<DeviceWriteReport*>(host) = DeviceWriteReport{};
    void* device = nullptr;
    if (cudaError_t e = cudaHostGetDevicePointer(&device, host, 0); e != cudaSuccess) {
      cudaFreeHost(host);
      return Status::Error(Format("cuda backend: the surface's report in device space: %s", cudaGetErrorString(e)));
    }
    m_host = static_cast<DeviceWriteReport*>(host);
    m_device = static_cast<DeviceWriteReport*>(device);
    return Status::Ok();
  }
  DeviceWriteReport* Device() { return m_device; }
  const volatile DeviceWriteReport* Host() const { return m_host; }

 private:
  DeviceWriteReport* m_host = nullptr;
  DeviceWriteReport* m_device = nullptr;
};
#endif

}  // namespace sphxr::sim
