#pragma once
// The probes on a backend's system (Traits as in backend_impl.h): the pressure sensors, the level gauges
// and their last readings, evaluated as one work item per probe over the current grid (ProbeStage,
// stages/probes.h). Empty: no probes, no probe work.
#include <thrust/memory.h>

#include <vector>

#include "launch/device.h"
#include "stages/probes.h"
#include "stages/views.h"

namespace sphxr::sim {

template <class Traits>
class ProbeArrays {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit ProbeArrays(DeviceOps<Traits>& device) : m_dev(device) {}

  bool Empty() const { return m_out.empty(); }

  void Set(const std::vector<Vec4>& points, const std::vector<ProbeLine>& lines) {
    // thrust's copy of an empty std::vector binds a reference to its null data (UBSan): clear instead.
    if (points.empty()) m_points.clear();
    else m_dev.Assign(m_points, points.begin(), points.end());
    if (lines.empty()) m_lines.clear();
    else m_dev.Assign(m_lines, lines.begin(), lines.end());
    m_dev.Resize(m_out, 2 * (points.size() + lines.size()));
    m_dev.Fill(m_out, 0.0f);
  }

  /// Two floats per probe, the last evaluation.
  void Values(std::vector<float>* out) const {
    out->resize(m_out.size());
    m_dev.Download(m_out.begin(), m_out.end(), out->begin(), /*asked=*/true);
  }

  /// One work item per probe, run by the backend's launcher (`Few`: the CPU runs them on the calling thread).
  template <class Launcher>
  void Evaluate(const GridView& grid, const FluidView& fluid, const Physics& physics, Launcher& launch) {
    const int points = static_cast<int>(m_points.size());
    const int items = points + static_cast<int>(m_lines.size());
    const ProbeStage stage{grid,          fluid, physics, thrust::raw_pointer_cast(m_points.data()), points,
                           thrust::raw_pointer_cast(m_lines.data()), thrust::raw_pointer_cast(m_out.data())};
    launch.Few(items, stage);
  }

 private:
  DeviceOps<Traits>& m_dev;
  Vector<Vec4> m_points;     // pressure sensors
  Vector<ProbeLine> m_lines;  // level gauges
  Vector<float> m_out;       // two floats per probe
};

}  // namespace sphxr::sim
