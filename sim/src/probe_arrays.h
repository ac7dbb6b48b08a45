#pragma once
// The probes on a backend's system (Traits as in backend_impl.h): the pressure sensors, the level gauges
// and their last readings, evaluated as one work item per probe over the current grid (ProbeStage,
// stages/probes.h). Empty: no probes, no probe work.
#include <thrust/copy.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/memory.h>

#include <vector>

#include "stages/probes.h"
#include "stages/views.h"

namespace sphxr::sim {

template <class Traits>
class ProbeArrays {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  bool Empty() const { return m_out.empty(); }

  void Set(const std::vector<Vec4>& points, const std::vector<ProbeLine>& lines) {
    // thrust's copy of an empty std::vector binds a reference to its null data (UBSan): clear instead.
    if (points.empty()) m_points.clear();
    else m_points.assign(points.begin(), points.end());
    if (lines.empty()) m_lines.clear();
    else m_lines.assign(lines.begin(), lines.end());
    m_out.resize(2 * (points.size() + lines.size()));
    thrust::fill(m_out.begin(), m_out.end(), 0.0f);
  }

  /// Two floats per probe, the last evaluation.
  void Values(std::vector<float>* out) const {
    out->resize(m_out.size());
    if (!out->empty()) thrust::copy(m_out.begin(), m_out.end(), out->begin());
  }

  void Evaluate(const GridView& grid, const FluidView& fluid, const Physics& physics) {
    const int points = static_cast<int>(m_points.size());
    const int items = points + static_cast<int>(m_lines.size());
    const ProbeStage stage{grid,          fluid, physics, thrust::raw_pointer_cast(m_points.data()), points,
                           thrust::raw_pointer_cast(m_lines.data()), thrust::raw_pointer_cast(m_out.data())};
    if constexpr (Traits::kSimdStages) {
      // The CPU: on the calling thread. A few dozen probes are tens of microseconds of work; a parallel
      // region for them cost more than that on a loaded machine (sphxr_bench_probes: the probes stage
      // took 5 % of a 2-thread step, 0.5 % of a 1-thread one).
      for (int k = 0; k < items; ++k) stage(k);
    } else {
      thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), items, stage);
    }
  }

 private:
  Vector<Vec4> m_points;     // pressure sensors
  Vector<ProbeLine> m_lines;  // level gauges
  Vector<float> m_out;       // two floats per probe
};

}  // namespace sphxr::sim
