#include "sphxr/sim/measure.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "sphxr/sim/host_grid.h"

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

EnergySummary SphEnergy(const SceneSetup& scene, float particleMass, const HostFluid& fluid,
                        const HostBoundary& boundary) {
  const SolverParams& p = scene.params;
  const double H = static_cast<double>(p.spacing) * p.supportFactor, rho0 = p.restDensity, B = p.stiffness;
  const double gamma = p.exponent, m = particleMass;
  const double sigma = 8.0 / (3.14159265358979323846 * H * H * H);
  auto W = [&](const Vec4& a, const Vec4& b) {  // the cubic spline (Monaghan 1992), support H, in double
    const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (r2 >= H * H) return 0.0;
    const double q = std::sqrt(r2) / H;
    if (q <= 0.5) return sigma * (6.0 * (q * q * q - q * q) + 1.0);
    const double t = 1.0 - q;
    return sigma * 2.0 * t * t * t;
  };
  // e(rho) = int_rho0^rho B ((s/rho0)^gamma - 1) / s^2 ds for rho > rho0.
  // (At gamma = 1, an allowed exponent, the first term's integral is log(s) / rho0.)
  auto F = [&](double r) {
    if (std::abs(gamma - 1.0) < 1e-12) return B * (std::log(r) / rho0 + 1.0 / r);
    return B * (std::pow(r / rho0, gamma) / ((gamma - 1.0) * r) + 1.0 / r);
  };
  auto e = [&](double rho) { return rho > rho0 ? F(rho) - F(rho0) : 0.0; };
  EnergySummary out;
  Vec3 lo, hi;
  BoundingBox({&fluid.position, &boundary.position}, &lo, &hi);
  const HostGrid fluidGrid(fluid.position, lo, hi, static_cast<float>(H) * 1.0001f);  // cells >= H despite rounding
  const HostGrid wallGrid(boundary.position, lo, hi, static_cast<float>(H) * 1.0001f);
  for (size_t i = 0; i < fluid.size(); ++i) {
    const Vec4 x = fluid.position[i], v = fluid.velocity[i];
    out.kinetic += 0.5 * m * (double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
    out.gravity -= m * (double(scene.gravity.x) * x.x + double(scene.gravity.y) * x.y + double(scene.gravity.z) * x.z);
    double rho = 0.0;
    fluidGrid.ForEachNear(Xyz(x), [&](uint32_t j) { rho += m * W(x, fluid.position[j]); });
    wallGrid.ForEachNear(Xyz(x), [&](uint32_t b) { rho += boundary.position[b].w * W(x, boundary.position[b]); });
    out.fluid += m * e(rho);
  }
  if (!boundary.invReference.empty()) {
    for (size_t b = 0; b < boundary.size(); ++b) {
      const double inv = boundary.invReference[b];
      if (!(inv > 0.0)) continue;
      const Vec4 y = boundary.position[b];
      double sum = 0.0;
      fluidGrid.ForEachNear(Xyz(y), [&](uint32_t j) { sum += W(y, fluid.position[j]); });
      out.walls += m * y.w / (rho0 * inv) * e(rho0 * sum * inv);
    }
  }
  return out;
}

namespace {

// Linear interpolation of the simulated series at time t (s); `member` picks front or height.
double SampleAt(const std::vector<DamBreakSample>& s, double DamBreakSample::*member, double t) {
  if (t <= s.front().t) return s.front().*member;
  const auto it = std::lower_bound(s.begin(), s.end(), t, [](const DamBreakSample& x, double v) { return x.t < v; });
  if (it == s.end()) return s.back().*member;
  const DamBreakSample& hi = *it;
  const DamBreakSample& lo = *(it - 1);
  const double w = (t - lo.t) / (hi.t - lo.t);
  return lo.*member + w * (hi.*member - lo.*member);
}

}  // namespace

bool ReadMartinMoyce(const std::string& path, std::vector<DamBreakPoint>* front, std::vector<DamBreakPoint>* height) {
  std::ifstream in(path);
  if (!in) return false;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("series", 0) == 0) continue;
    const size_t a = line.find(','), b = a == std::string::npos ? a : line.find(',', a + 1);
    if (b == std::string::npos) return false;
    const std::string series = line.substr(0, a);
    char* end = nullptr;
    const double t = std::strtod(line.c_str() + a + 1, &end);
    if (end != line.c_str() + b) return false;
    const double v = std::strtod(line.c_str() + b + 1, &end);
    if (end == line.c_str() + b + 1 || !std::isfinite(t) || !std::isfinite(v)) return false;
    if (series == "front") front->push_back({t, v});
    else if (series == "height") height->push_back({t, v});
    else return false;
  }
  return !front->empty() && !height->empty();
}

bool JudgeMartinMoyce(const std::vector<DamBreakSample>& samples, const std::vector<DamBreakPoint>& measuredFront,
                      const std::vector<DamBreakPoint>& measuredHeight, double a, double g, DamBreakJudgement* out,
                      double frontTMin, double frontTMax, double heightTauMax) {
  *out = DamBreakJudgement{};
  if (samples.size() < 2 || measuredFront.empty()) return false;
  const double toT = std::sqrt(2.0 * g / a), toTau = std::sqrt(g / a);
  const double tEnd = samples.back().t;
  // The compared points: those the run reached without a lag (so every lag compares the same points).
  struct Compared {
    double t;  // s
    double ownT, value;
    bool front;
  };
  std::vector<Compared> points;
  for (const DamBreakPoint& m : measuredFront) {
    if (m.t >= frontTMin && m.t <= frontTMax && m.t / toT <= tEnd) points.push_back({m.t / toT, m.t, m.value, true});
  }
  for (const DamBreakPoint& m : measuredHeight) {
    if (m.t <= heightTauMax && m.t / toTau <= tEnd) points.push_back({m.t / toTau, m.t, m.value, false});
  }
  if (points.empty()) return false;
  auto simulated = [&](const Compared& c, double lag) {
    return SampleAt(samples, c.front ? &DamBreakSample::front : &DamBreakSample::height, c.t - lag);
  };
  // The lag: a scan in steps of 0.05 ms (the deviations are smooth in it; a step well under a time step).
  out->lagLimit = measuredFront.front().t / toT;
  const int steps = static_cast<int>(std::ceil(out->lagLimit / 5e-5));
  double best = INFINITY;
  for (int k = 0; k <= steps; ++k) {
    const double lag = out->lagLimit * k / steps;
    double sse = 0.0;
    for (const Compared& c : points) {
      const double rel = simulated(c, lag) / c.value - 1.0;
      sse += rel * rel;
    }
    if (sse < best) {
      best = sse;
      out->lag = lag;
    }
  }
  double frontSq = 0.0, frontSum = 0.0;
  for (const Compared& c : points) {
    const double sim = simulated(c, out->lag);
    const DamBreakJudgement::Deviation d{c.ownT, c.value, sim, sim / c.value - 1.0};
    if (c.front) {
      out->front.push_back(d);
      frontSq += d.relative * d.relative;
      frontSum += d.relative;
      out->frontMax = std::max(out->frontMax, std::fabs(d.relative));
    } else {
      out->height.push_back(d);
      out->heightMax = std::max(out->heightMax, std::fabs(d.relative));
    }
  }
  if (!out->front.empty()) {
    out->frontRms = std::sqrt(frontSq / static_cast<double>(out->front.size()));
    out->frontBias = frontSum / static_cast<double>(out->front.size());
  }
  return true;
}

}  // namespace sphxr::sim
