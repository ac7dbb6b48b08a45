#pragma once
// A plain uniform grid over points on the host: for measurements that must not lean on the solver's own
// neighbour grid (bench/perf.cpp's brute-force pair count, measure.h's SphEnergy) and the one-off kernel sums over
// a moving body's own particles (Solver::InitBodies).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include "sphxr/sim/vec.h"

namespace sphxr::sim {

/// The bounding box of one or more point sets (lo = hi = 0 when all are empty).
inline void BoundingBox(std::initializer_list<const std::vector<Vec4>*> sets, Vec3* lo, Vec3* hi) {
  bool any = false;
  for (const std::vector<Vec4>* set : sets) {
    for (const Vec4& p : *set) {
      if (!any) *lo = *hi = Xyz(p);
      any = true;
      *lo = Vec3{std::min(lo->x, p.x), std::min(lo->y, p.y), std::min(lo->z, p.z)};
      *hi = Vec3{std::max(hi->x, p.x), std::max(hi->y, p.y), std::max(hi->z, p.z)};
    }
  }
  if (!any) *lo = *hi = Vec3{0.0f, 0.0f, 0.0f};
}

/// A uniform grid (cells of `cell`, at least the support radius) over a set of points, in CSR form.
/// Points outside [lo, hi] fall into the edge cells, so a neighbour is never missed, only found later.
class HostGrid {
 public:
  HostGrid(const std::vector<Vec4>& points, Vec3 lo, Vec3 hi, float cell) : m_lo(lo), m_cell(cell) {
    m_n[0] = std::max(1, static_cast<int>(std::ceil((hi.x - lo.x) / cell)) + 1);
    m_n[1] = std::max(1, static_cast<int>(std::ceil((hi.y - lo.y) / cell)) + 1);
    m_n[2] = std::max(1, static_cast<int>(std::ceil((hi.z - lo.z) / cell)) + 1);
    const size_t cells = static_cast<size_t>(m_n[0]) * m_n[1] * m_n[2];
    m_start.assign(cells + 1, 0);
    std::vector<uint32_t> cellOf(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      int c[3];
      Cell(Xyz(points[i]), c);
      cellOf[i] = static_cast<uint32_t>(Linear(c[0], c[1], c[2]));
      ++m_start[cellOf[i] + 1];
    }
    for (size_t c = 0; c < cells; ++c) m_start[c + 1] += m_start[c];
    m_index.resize(points.size());
    std::vector<uint32_t> fill(m_start.begin(), m_start.end() - 1);
    for (size_t i = 0; i < points.size(); ++i) m_index[fill[cellOf[i]]++] = static_cast<uint32_t>(i);
  }

  void Cell(Vec3 p, int c[3]) const {
    const float v[3] = {p.x - m_lo.x, p.y - m_lo.y, p.z - m_lo.z};
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(static_cast<int>(std::floor(v[a] / m_cell)), 0, m_n[a] - 1);
  }
  size_t Linear(int x, int y, int z) const { return static_cast<size_t>(x) + m_n[0] * (y + static_cast<size_t>(m_n[1]) * z); }

  /// Calls f(j) for every point j in the 27 cells around p.
  template <class F>
  void ForEachNear(Vec3 p, F&& f) const {
    int c[3];
    Cell(p, c);
    for (int z = std::max(0, c[2] - 1); z <= std::min(m_n[2] - 1, c[2] + 1); ++z) {
      for (int y = std::max(0, c[1] - 1); y <= std::min(m_n[1] - 1, c[1] + 1); ++y) {
        for (int x = std::max(0, c[0] - 1); x <= std::min(m_n[0] - 1, c[0] + 1); ++x) {
          const size_t cell = Linear(x, y, z);
          for (uint32_t k = m_start[cell]; k < m_start[cell + 1]; ++k) f(m_index[k]);
        }
      }
    }
  }

 private:
  Vec3 m_lo;
  float m_cell;
  int m_n[3];
  std::vector<uint32_t> m_start;  // cells + 1 offsets into m_index
  std::vector<uint32_t> m_index;  // point indices grouped by cell
};

}  // namespace sphxr::sim
