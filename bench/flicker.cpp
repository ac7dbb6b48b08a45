// How much the pressure of still water flickers, per density model (solver.density): a column 0.3 m
// deep (hydrostatic start, walls with their own density, c = 10x sqrt(2 g depth)) runs 0.6 s, then over
// the next 0.3 s every 10th step samples
//   - the fraction of the particles 0.1-0.2 m below the surface whose pressure is 0 (the clamp at zero),
//   - a wall probe at depth 0.15 m, half a spacing from the x- wall: the Shepard average
//     sum_j V_j p_j W / sum_j V_j W of the fluid pressure, against rho0 g depth.
// Usage: sphxr_bench_flicker [summation|delta_sph ...] (default: both). Prints one line per model.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace {

using namespace sphxr;

constexpr float kDepth = 0.3f, kDx = 0.01f, kRho = 1000.0f, kG = 9.81f;

double Kernel(double r, double h) {  // the solver's cubic spline with support h (sim/src/kernel.h)
  const double q = r / h;
  if (q >= 1.0) return 0.0;
  const double s = 8.0 / (3.14159265358979 * h * h * h);
  return q <= 0.5 ? s * (6.0 * (q * q * q - q * q) + 1.0) : s * 2.0 * std::pow(1.0 - q, 3);
}

int Run(const std::string& model) {
  sim::SceneSetup s;
  if (!sim::ParseDensityModel(model, &s.density)) {
    std::fprintf(stderr, "unknown density model %s\n", model.c_str());
    return 2;
  }
  s.params.spacing = kDx;
  const float c = 10.0f * std::sqrt(2.0f * kG * kDepth);
  s.params.stiffness = kRho * c * c / 7.0f;
  s.params.viscosity = 0.02f;
  s.params.boundaryViscosity = 0.02f;
  s.params.maxDt = 0.001f;
  s.tank = {{0, 0, 0}, {0.2f, 0.4f, 0.1f}};
  s.wallPressure = sim::SceneSetup::WallPressure::kWallDensity;
  sim::FluidBlock block{{{0, 0, 0}, {0.2f, kDepth, 0.1f}}, {}};
  block.hydrostatic = true;
  s.fluid.push_back(block);
  std::unique_ptr<sim::Solver> solver;
  sim::SolverConfig config;
  config.threads = 1;  // a busy machine: two threads wait for each other at every stage
  if (Status st = sim::Solver::Create(s, config, &solver); !st) {
    std::fprintf(stderr, "%s\n", st.message().c_str());
    return 1;
  }
  const double h = solver->SupportRadius();
  const double mass = solver->ParticleMass();
  sim::HostFluid f;
  int64_t band = 0, zero = 0;
  std::vector<double> probe;
  while (solver->Time() < 0.9) {
    if (Status st = solver->Step(); !st) {
      std::fprintf(stderr, "%s\n", st.message().c_str());
      return 1;
    }
    if (solver->Time() < 0.6 || solver->GetTotals().steps % 10 != 0) continue;
    solver->Download(&f);
    float top = 0.0f;
    for (const sim::Vec4& p : f.position) top = std::max(top, p.y);
    top += 0.5f * kDx;  // the surface: half a spacing above the top layer
    double num = 0.0, den = 0.0;
    const double px = 0.5 * kDx, py = top - 0.15, pz = 0.05;
    for (size_t i = 0; i < f.size(); ++i) {
      const double depth = top - f.position[i].y;
      if (depth >= 0.1 && depth <= 0.2) {
        ++band;
        zero += f.pressure[i] <= 0.0f ? 1 : 0;
      }
      const double dx = f.position[i].x - px, dy = f.position[i].y - py, dz = f.position[i].z - pz;
      const double w = mass / f.density[i] * Kernel(std::sqrt(dx * dx + dy * dy + dz * dz), h);
      num += w * f.pressure[i];
      den += w;
    }
    probe.push_back(den > 0.0 ? num / den : 0.0);
  }
  double mean = 0.0, sq = 0.0, lo = 1e30, hi = -1e30;
  for (double p : probe) {
    mean += p;
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  mean /= static_cast<double>(probe.size());
  for (double p : probe) sq += (p - mean) * (p - mean);
  const double hydro = kRho * kG * 0.15;
  const sim::Totals& t = solver->GetTotals();
  std::printf("%-10s p=0 in 0.1-0.2 m depth: %5.1f %% of %lld samples; wall probe at 0.15 m: mean %.0f Pa (rho0 g d %.0f), "
              "std %.0f Pa, min %.0f, max %.0f; %.3f ms/step; clamps %.3g per 1,000 particle-steps\n",
              model.c_str(), 100.0 * static_cast<double>(zero) / static_cast<double>(band), static_cast<long long>(band),
              mean, hydro, std::sqrt(sq / static_cast<double>(probe.size())), lo, hi,
              1e3 * t.stepSeconds / static_cast<double>(t.steps),
              1e3 * static_cast<double>(t.clampedEvents) / static_cast<double>(t.particleSteps));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> models;
  for (int i = 1; i < argc; ++i) models.push_back(argv[i]);
  if (models.empty()) models = {"summation", "delta_sph"};
  for (const std::string& m : models) {
    if (int rc = Run(m); rc != 0) return rc;
  }
  return 0;
}
