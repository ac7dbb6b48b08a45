#include "sphxr/sim/measure.h"

#include <algorithm>
#include <cmath>
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

}  // namespace sphxr::sim
