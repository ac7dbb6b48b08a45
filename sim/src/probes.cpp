// Probes (sphxr/sim/probes.h): checking a probe set, the dry thresholds, and turning the probe stage's
// sums (stages/probes.h) into readings.
#include "sphxr/sim/probes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "backend.h"
#include "kernel.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {
namespace {

std::string Str(Vec3 v) { return Format("[%g, %g, %g]", v.x, v.y, v.z); }

bool Inside(const Aabb& box, Vec3 p) {
  return p.x >= box.min.x && p.x <= box.max.x && p.y >= box.min.y && p.y <= box.max.y && p.z >= box.min.z &&
         p.z <= box.max.z;
}

}  // namespace

float KernelFractionInside(float offset, float supportRadius) {
  // The kernel's mass in the slab [0, offset] along the normal, added to the half on the water's side:
  // w1(z) = 2 pi int_{|z|}^{H} W(s) s ds is the kernel integrated over the plane at height z. Simpson's
  // rule on both integrals (the kernel is a piecewise cubic: 64 intervals each are exact to float).
  const float H = supportRadius;
  if (!(offset > 0.0f)) return 0.5f;
  if (offset >= H) return 1.0f;
  const CubicSpline k = CubicSpline::Make(H);
  auto simpson = [](double a, double b, int n, auto&& f) {
    const double h = (b - a) / n;
    double sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
    return sum * h / 3.0;
  };
  auto plane = [&](double z) {
    return 2.0 * M_PI * simpson(z, H, 64, [&](double s) { return static_cast<double>(k.W(static_cast<float>(s))) * s; });
  };
  return static_cast<float>(0.5 + simpson(0.0, offset, 64, plane));
}

namespace {

/// The kernel's integral over the box [lo, hi] (relative to the kernel's centre), clipped to its support's
/// cube: composite Simpson, 32 intervals an axis (the kernel is C2, so the rule's error is far below the
/// thresholds' needs; tests/sim/probes_test.cpp holds it to the flat wall's exact fraction).
double KernelBoxIntegral(Vec3 lo, Vec3 hi, const CubicSpline& k) {
  const double H = k.H;
  const double a[3] = {std::max<double>(lo.x, -H), std::max<double>(lo.y, -H), std::max<double>(lo.z, -H)};
  const double b[3] = {std::min<double>(hi.x, H), std::min<double>(hi.y, H), std::min<double>(hi.z, H)};
  if (!(a[0] < b[0] && a[1] < b[1] && a[2] < b[2])) return 0.0;
  constexpr int n = 32;
  double h[3], w[n + 1];
  for (int d = 0; d < 3; ++d) h[d] = (b[d] - a[d]) / n;
  for (int i = 0; i <= n; ++i) w[i] = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double x = a[0] + i * h[0];
    for (int j = 0; j <= n; ++j) {
      const double y = a[1] + j * h[1], xy2 = x * x + y * y;
      if (xy2 >= H * H) continue;
      double row = 0.0;
      for (int l = 0; l <= n; ++l) {
        const double z = a[2] + l * h[2];
        row += w[l] * static_cast<double>(k.W(static_cast<float>(std::sqrt(xy2 + z * z))));
      }
      sum += w[i] * w[j] * row;
    }
  }
  return sum * h[0] * h[1] * h[2] / 27.0;
}

bool Overlaps(const Aabb& box, Vec3 lo, Vec3 hi) {
  return box.min.x < hi.x && box.max.x > lo.x && box.min.y < hi.y && box.max.y > lo.y && box.min.z < hi.z &&
         box.max.z > lo.z;
}

}  // namespace

float KernelFractionInRegion(Vec3 point, const Aabb& tank, const std::vector<Aabb>& obstacles, float supportRadius) {
  const float H = supportRadius;
  const Vec3 lo = point - Vec3{H, H, H}, hi = point + Vec3{H, H, H};
  bool nearObstacle = false;
  for (const Aabb& o : obstacles) nearObstacle = nearObstacle || Overlaps(o, lo, hi);
  // The tank's faces within the support, and the distance to the nearest.
  const float gaps[6] = {point.x - tank.min.x, tank.max.x - point.x, point.y - tank.min.y,
                         tank.max.y - point.y, point.z - tank.min.z, tank.max.z - point.z};
  int faces = 0;
  float nearest = H;
  for (const float g : gaps) {
    if (g < H) ++faces;
    nearest = std::min(nearest, g);
  }
  if (!nearObstacle && faces == 0) return 1.0f;
  if (!nearObstacle && faces == 1) return KernelFractionInside(nearest, H);  // exact: one flat face
  const CubicSpline k = CubicSpline::Make(H);
  double inside = KernelBoxIntegral(tank.min - point, tank.max - point, k);
  for (const Aabb& o : obstacles) {  // (obstacles that overlap each other are taken out twice: clamped)
    const Aabb solid{{std::max(o.min.x, tank.min.x), std::max(o.min.y, tank.min.y), std::max(o.min.z, tank.min.z)},
                     {std::min(o.max.x, tank.max.x), std::min(o.max.y, tank.max.y), std::min(o.max.z, tank.max.z)}};
    inside -= KernelBoxIntegral(solid.min - point, solid.max - point, k);
  }
  return static_cast<float>(std::clamp(inside, 0.0, 1.0));
}

float ProbeDryThreshold(Vec3 point, const Aabb& tank, const std::vector<Aabb>& obstacles, float supportRadius) {
  return kDryFraction * KernelFractionInRegion(point, tank, obstacles, supportRadius);
}

Status Solver::UploadProbes(const ProbeSet& probes, std::vector<float>* dry) {
  const Aabb& tank = m_scene.tank;
  const float dx = m_scene.params.spacing;
  const float support = SupportRadius();
  std::vector<Vec4> points;
  std::vector<ProbeLine> lines;
  dry->clear();
  for (const PressureProbe& p : probes.pressure) {
    const std::string who = "probe '" + p.name + "'";
    if (!Finite(p.at) || !Finite(p.normal)) return Status::Error(who + ": at and normal must be finite numbers");
    const float length = Length(p.normal);
    const bool wall = length > 0.0f;
    if (wall && std::fabs(length - 1.0f) > 1e-3f) {
      return Status::Error(who + ": normal " + Str(p.normal) + " must be a unit vector (or zero for a point in the water)");
    }
    const float offset = p.offset.value_or(wall ? 0.5f * dx : 0.0f);
    if (!(offset >= 0.0f) || !std::isfinite(offset)) return Status::Error(who + Format(": offset %g must be 0 or more", offset));
    const Vec3 x = wall ? p.at - p.normal * offset : p.at;
    if (!Inside(tank, x)) {
      return Status::Error(who + ": its point " + Str(x) + " is outside the tank " + Str(tank.min) + " .. " +
                           Str(tank.max));
    }
    points.push_back(MakeVec4(x));
    dry->push_back(ProbeDryThreshold(x, tank, m_scene.obstacles, support));
  }
  for (const LevelGauge& g : probes.level) {
    const std::string who = "gauge '" + g.name + "'";
    const float bottom = g.bottom.value_or(tank.min.y), top = g.top.value_or(tank.max.y);
    if (!std::isfinite(g.x) || !std::isfinite(g.z) || !std::isfinite(bottom) || !std::isfinite(top)) {
      return Status::Error(who + ": x, z, bottom and top must be finite numbers");
    }
    if (g.x < tank.min.x || g.x > tank.max.x || g.z < tank.min.z || g.z > tank.max.z) {
      return Status::Error(who + Format(": its line at x = %g, z = %g is outside the tank", g.x, g.z) + " " +
                           Str(tank.min) + " .. " + Str(tank.max));
    }
    if (!(bottom < top) || bottom < tank.min.y || top > tank.max.y) {
      return Status::Error(who + Format(": bottom %g and top %g must lie in the tank's height %g .. %g, bottom below top",
                                        bottom, top, tank.min.y, tank.max.y));
    }
    lines.push_back(ProbeLine{g.x, g.z, bottom, top, kLevelCoarse * dx, kLevelFine * dx});
  }
  for (const ForceProbe& f : probes.force) {
    if (f.body < 0 || f.body >= BodyCount()) {
      return Status::Error("force probe '" + f.name + Format("': body %d does not exist (the scene has %d)", f.body, BodyCount()));
    }
  }
  m_backend->SetProbes(points, lines);
  return Status::Ok();
}

Status Solver::SetProbes(const ProbeSet& probes) {
  std::vector<float> dry;
  if (Status s = UploadProbes(probes, &dry); !s) {
    (void)UploadProbes(m_probes, &m_probeDry);  // (checked when it was set) the set before stays
    return s;
  }
  m_probes = probes;
  m_probeDry = std::move(dry);
  m_probeSample = ProbeSample{};
  return Status::Ok();
}

Status Solver::SampleProbes(const ProbeSet& probes, ProbeSample* out) {
  std::vector<float> dry;
  if (Status s = UploadProbes(probes, &dry); !s) {
    (void)UploadProbes(m_probes, &m_probeDry);
    return s;
  }
  SampleProbesNow();
  ReadProbes(probes, dry, Time(), m_stepBase + m_totals.steps, out);
  return UploadProbes(m_probes, &m_probeDry);  // the set the steps evaluate, as it was
}

void Solver::ReadProbes(const ProbeSet& probes, const std::vector<float>& dry, double time, int64_t steps,
                        ProbeSample* out) const {
  std::vector<float> sums;
  m_backend->ProbeValues(&sums);
  const size_t np = probes.pressure.size(), nl = probes.level.size();
  SPHXR_ASSERT(sums.size() == 2 * (np + nl));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out->time = time;
  out->steps = steps;
  out->pressure.resize(np);
  out->shepard.resize(np);
  for (size_t k = 0; k < np; ++k) {
    const float weighted = sums[2 * k], sum = sums[2 * k + 1];
    out->shepard[k] = sum;
    out->pressure[k] = sum >= dry[k] && sum > 0.0f ? weighted / sum : nan;
  }
  out->level.resize(nl);
  for (size_t k = 0; k < nl; ++k) {
    const float* s = &sums[2 * (np + k)];
    out->level[k] = s[1] != 0.0f ? s[0] : nan;
  }
  out->load.resize(probes.force.size());
  for (size_t k = 0; k < probes.force.size(); ++k) {
    const int b = probes.force[k].body;
    out->load[k] = b < static_cast<int>(m_bodyLoads.size()) ? m_bodyLoads[b] : BodyLoad{};
  }
}

}  // namespace sphxr::sim
