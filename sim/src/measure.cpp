#include "sphxr/sim/measure.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace sphxr::sim {

float ConnectedExtent(const HostFluid& fluid, int axis, float wall, float spacing, int minPerBin, float bandWall,
                      float band) {
  auto coord = [&](const Vec4& p) { return axis == 0 ? p.x : p.y; };
  std::vector<int> count;
  std::vector<float> outer;
  for (const Vec4& p : fluid.position) {
    if (band > 0.0f && (p.x - bandWall) > band) continue;
    const float d = coord(p) - wall;
    if (!(d >= 0.0f)) continue;
    const size_t bin = static_cast<size_t>(d / spacing);
    if (bin > 1u << 24) continue;
    if (bin >= count.size()) {
      count.resize(bin + 1, 0);
      outer.resize(bin + 1, 0.0f);
    }
    ++count[bin];
    outer[bin] = std::max(outer[bin], d);
  }
  float extent = 0.0f;
  for (size_t b = 0; b < count.size() && count[b] >= std::max(1, minPerBin); ++b) extent = outer[b] + 0.5f * spacing;
  return extent;
}

MomentumSummary Momentum(const HostFluid& fluid) {
  MomentumSummary m;
  for (const Vec4& v : fluid.velocity) {
    m.px += v.x;
    m.py += v.y;
    m.pz += v.z;
    m.sumAbs += std::sqrt(static_cast<double>(v.x) * v.x + static_cast<double>(v.y) * v.y + static_cast<double>(v.z) * v.z);
  }
  return m;
}

namespace {

// Points binned on a grid of cells one support radius wide: the neighbours of x within the support lie in
// the 27 cells around it.
class PointGrid {
 public:
  PointGrid(const std::vector<Vec4>& points, double cell) : m_points(points), m_cell(cell) {
    for (size_t i = 0; i < points.size(); ++i) m_cells[Key(points[i].x, points[i].y, points[i].z, 0, 0, 0)].push_back(i);
  }
  template <class F>
  void ForNear(double x, double y, double z, F&& f) const {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = m_cells.find(Key(x, y, z, dx, dy, dz));
          if (it == m_cells.end()) continue;
          for (size_t j : it->second) {
            const Vec4 q = m_points[j];
            f(j, x - q.x, y - q.y, z - q.z);
          }
        }
  }

 private:
  uint64_t Key(double x, double y, double z, int dx, int dy, int dz) const {
    auto c = [&](double v, int d) { return static_cast<uint64_t>(static_cast<int64_t>(std::floor(v / m_cell)) + d + (1 << 20)) & 0x1fffff; };
    return c(x, dx) | (c(y, dy) << 21) | (c(z, dz) << 42);
  }
  const std::vector<Vec4>& m_points;
  double m_cell;
  std::unordered_map<uint64_t, std::vector<size_t>> m_cells;
};

}  // namespace

EnergySummary SphEnergy(const SceneSetup& scene, float particleMass, const HostFluid& fluid,
                        const HostBoundary& boundary) {
  const SolverParams& p = scene.params;
  const double H = static_cast<double>(p.spacing) * p.supportFactor, rho0 = p.restDensity, B = p.stiffness;
  const double gamma = p.exponent, m = particleMass;
  const double sigma = 8.0 / (3.14159265358979323846 * H * H * H);
  auto W = [&](double r2) {  // the cubic spline (Monaghan 1992) with support H
    if (r2 >= H * H) return 0.0;
    const double q = std::sqrt(r2) / H;
    if (q <= 0.5) return sigma * (6.0 * (q * q * q - q * q) + 1.0);
    const double t = 1.0 - q;
    return sigma * 2.0 * t * t * t;
  };
  // e(rho) = int_rho0^rho B ((s/rho0)^gamma - 1) / s^2 ds for rho > rho0.
  auto F = [&](double r) { return B * (std::pow(r / rho0, gamma) * r / ((gamma - 1.0) * r * r) + 1.0 / r); };
  auto e = [&](double rho) { return rho > rho0 ? F(rho) - F(rho0) : 0.0; };
  EnergySummary out;
  const PointGrid fluidGrid(fluid.position, H), wallGrid(boundary.position, H);
  for (size_t i = 0; i < fluid.size(); ++i) {
    const Vec4 x = fluid.position[i], v = fluid.velocity[i];
    out.kinetic += 0.5 * m * (double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
    out.gravity -= m * (double(scene.gravity.x) * x.x + double(scene.gravity.y) * x.y + double(scene.gravity.z) * x.z);
    double rho = 0.0;
    fluidGrid.ForNear(x.x, x.y, x.z, [&](size_t, double dx, double dy, double dz) { rho += m * W(dx * dx + dy * dy + dz * dz); });
    wallGrid.ForNear(x.x, x.y, x.z, [&](size_t b, double dx, double dy, double dz) {
      rho += boundary.position[b].w * W(dx * dx + dy * dy + dz * dz);
    });
    out.fluid += m * e(rho);
  }
  if (!boundary.invReference.empty()) {
    for (size_t b = 0; b < boundary.size(); ++b) {
      const double inv = boundary.invReference[b];
      if (!(inv > 0.0)) continue;
      const Vec4 y = boundary.position[b];
      double sum = 0.0;
      fluidGrid.ForNear(y.x, y.y, y.z, [&](size_t, double dx, double dy, double dz) { sum += W(dx * dx + dy * dy + dz * dz); });
      out.walls += m * y.w / (rho0 * inv) * e(rho0 * sum * inv);
    }
  }
  return out;
}

}  // namespace sphxr::sim
