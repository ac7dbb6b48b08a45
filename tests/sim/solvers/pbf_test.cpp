// Position-based fluids (sim/src/solvers/pbf/pbf.h, Macklin & Müller 2013): one step against the paper's
// algorithm written out here by brute force over every particle pair, in double; still water from the
// lattice; the extremes of the iteration count. (The same bits at every thread count, a restore, cpu
// against cpu-reference: the conformance suite, conformance_test.cpp; against CUDA:
// tests/backend/agreement_test.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>

#include "kernel.h"
#include "scene_check.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr {
namespace {

using sim::SceneSetup;
using sim::Vec3;
using sim::Vec4;

SceneSetup PbfBox(Vec3 tank, Vec3 fluid, float spacing) {
  SceneSetup s = test::TankScene({0, 0, 0}, tank, spacing);
  s.method = sim::SolverMethod::kPbf;
  s.openTop = false;
  s.fluid.push_back(test::Block({0, 0, 0}, fluid));
  return s;
}

struct D3 {
  double x = 0, y = 0, z = 0;
  D3 operator+(D3 o) const { return {x + o.x, y + o.y, z + o.z}; }
  D3 operator-(D3 o) const { return {x - o.x, y - o.y, z - o.z}; }
  D3 operator*(double s) const { return {x * s, y * s, z * s}; }
  double Dot(D3 o) const { return x * o.x + y * o.y + z * o.z; }
  D3 Cross(D3 o) const { return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x}; }
  double Length() const { return std::sqrt(Dot(*this)); }
};
D3 Of(Vec4 v) { return {v.x, v.y, v.z}; }

/// The cubic spline of sim/src/kernel.h, in double: W(r) and grad W(d) = d W'(r) / r.
struct Spline {
  double H;
  double sigma = 8.0 / (M_PI * H * H * H);
  double W(double r) const {
    const double q = r / H;
    if (q >= 1.0) return 0.0;
    if (q <= 0.5) return sigma * (6.0 * (q * q * q - q * q) + 1.0);
    return sigma * 2.0 * (1.0 - q) * (1.0 - q) * (1.0 - q);
  }
  D3 Grad(D3 d) const {
    const double r = std::sqrt(d.Dot(d));
    const double q = r / H;
    if (q >= 1.0 || r == 0.0) return {};
    const double dw = q <= 0.5 ? sigma * 6.0 * (3.0 * q * q - 2.0 * q) / H : -sigma * 6.0 * (1.0 - q) * (1.0 - q) / H;
    return d * (dw / r);
  }
};

/// MM13's vorticity confinement (eq. 15-16) over given neighbour sets, in double: omega_i = sum_j V
/// (v_i - v_j) x grad_i W_ij, eta_i = sum_j V (|omega_j| - |omega_i|) grad_i W_ij, and the velocity
/// change dt eps (N x omega_i) with N = eta / |eta| (proportional to eta under 1e-3 |omega_i| / H, as the
/// stage does).
std::vector<D3> Vorticity(const Spline& k, double volume, const std::vector<D3>& x, const std::vector<D3>& v,
                          const std::vector<std::vector<size_t>>& near) {
  std::vector<D3> w(x.size());
  for (size_t i = 0; i < x.size(); ++i)
    for (size_t j : near[i]) w[i] = w[i] + (v[i] - v[j]).Cross(k.Grad(x[i] - x[j])) * volume;
  return w;
}
std::vector<D3> Confinement(const Spline& k, double volume, double eps, double dt, const std::vector<D3>& x,
                            const std::vector<D3>& w, const std::vector<std::vector<size_t>>& near) {
  std::vector<D3> dv(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    D3 eta;
    for (size_t j : near[i]) eta = eta + k.Grad(x[i] - x[j]) * ((w[j].Length() - w[i].Length()) * volume);
    const double length = std::max(eta.Length(), 1e-3 * w[i].Length() / k.H);
    if (length > 0.0) dv[i] = (eta * (1.0 / length)).Cross(w[i]) * (eps * dt);
  }
  return dv;
}

/// MM13's Algorithm 1 for one step of dt, every sum over all pairs: predict, the neighbour sets at x*,
/// `iterations` Jacobi iterations of lambda (eq. 11, with epsilon) and the correction (eq. 12, with
/// s_corr, eq. 13), each followed by the collision response (a particle kept half a spacing from every
/// face of the closed box), v = (x* - x) / dt, XSPH (eq. 17). The walls are Akinci's boundary particles
/// (w = Psi_b) in the density, in grad_i C_i and in the correction with lambda_i.
struct Reference {
  const SceneSetup& scene;
  std::vector<Vec4> boundary;
  std::vector<D3> x, v;
  std::vector<double> density;

  /// sum_k |grad_k C_i|^2 over a particle's neighbours in the rest lattice (epsilon's and s_corr's scale).
  double RestSum(const Spline& k, double dx, double volume) const {
    double sum = 0.0;
    const int reach = static_cast<int>(std::ceil(k.H / dx));
    for (int a = -reach; a <= reach; ++a)
      for (int b = -reach; b <= reach; ++b)
        for (int c = -reach; c <= reach; ++c) {
          const D3 g = k.Grad(D3{a * dx, b * dx, c * dx}) * volume;
          sum += g.Dot(g);
        }
    return sum;
  }

  void Step(double dt) {
    const auto& p = scene.params;
    const Spline k{p.spacing * p.supportFactor};
    const double dx = p.spacing, rho0 = p.restDensity, volume = dx * dx * dx, mass = rho0 * volume;
    const double d0 = RestSum(k, dx, volume);
    const double eps = p.pbfRelaxation * d0, corrK = p.pbfCorrK / d0, wdq = k.W(p.pbfCorrDq * k.H);
    const D3 lo{scene.tank.min.x + 0.5 * dx, scene.tank.min.y + 0.5 * dx, scene.tank.min.z + 0.5 * dx};
    const D3 hi{scene.tank.max.x - 0.5 * dx, scene.tank.max.y - 0.5 * dx, scene.tank.max.z - 0.5 * dx};
    auto collide = [&](D3* q) {
      q->x = std::clamp(q->x, lo.x, hi.x);
      q->y = std::clamp(q->y, lo.y, hi.y);
      q->z = std::clamp(q->z, lo.z, hi.z);
    };
    const size_t n = x.size();
    const D3 g{scene.gravity.x, scene.gravity.y, scene.gravity.z};
    std::vector<D3> start = x;
    for (size_t i = 0; i < n; ++i) {
      v[i] = v[i] + g * dt;
      x[i] = x[i] + v[i] * dt;
      collide(&x[i]);
    }
    std::vector<std::vector<size_t>> near(n);
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) {
        const D3 d = x[i] - x[j];
        if (j != i && d.Dot(d) < k.H * k.H) near[i].push_back(j);
      }
    std::vector<double> lambda(n);
    density.assign(n, 0.0);
    for (int it = 0; it < static_cast<int>(p.pbfIterations); ++it) {
      for (size_t i = 0; i < n; ++i) {
        double sumW = k.W(0.0), sum2 = 0.0, walls = 0.0;
        D3 gradI;
        for (size_t j : near[i]) {
          const D3 d = x[i] - x[j];
          sumW += k.W(std::sqrt(d.Dot(d)));
          const D3 gj = k.Grad(d) * volume;
          gradI = gradI + gj;
          sum2 += gj.Dot(gj);
        }
        for (const Vec4& b : boundary) {
          const D3 d = x[i] - Of(b);
          walls += b.w * k.W(std::sqrt(d.Dot(d)));
          gradI = gradI + k.Grad(d) * (b.w / rho0);
        }
        density[i] = mass * sumW + walls;
        const double c = std::max(density[i] / rho0 - 1.0, 0.0);
        lambda[i] = -c / (sum2 + gradI.Dot(gradI) + eps);
      }
      std::vector<D3> delta(n);
      for (size_t i = 0; i < n; ++i) {
        for (size_t j : near[i]) {
          const D3 d = x[i] - x[j];
          const double corr = -corrK * std::pow(k.W(std::sqrt(d.Dot(d))) / wdq, p.pbfCorrN);
          delta[i] = delta[i] + k.Grad(d) * ((lambda[i] + lambda[j] + corr) * volume);
        }
        for (const Vec4& b : boundary) delta[i] = delta[i] + k.Grad(x[i] - Of(b)) * (lambda[i] * b.w / rho0);
      }
      for (size_t i = 0; i < n; ++i) {
        x[i] = x[i] + delta[i];
        collide(&x[i]);
      }
    }
    for (size_t i = 0; i < n; ++i) v[i] = (x[i] - start[i]) * (1.0 / dt);
    std::vector<D3> dv(n);
    for (size_t i = 0; i < n; ++i)
      for (size_t j : near[i]) {
        const D3 d = x[i] - x[j];
        dv[i] = dv[i] + (v[j] - v[i]) * (k.W(std::sqrt(d.Dot(d))) * p.pbfXsph * volume);
      }
    for (size_t i = 0; i < n; ++i) v[i] = v[i] + dv[i];
    if (p.pbfVorticity > 0.0f) {
      const std::vector<D3> w = Vorticity(k, volume, x, v, near);
      const std::vector<D3> kick = Confinement(k, volume, p.pbfVorticity, dt, x, w, near);
      for (size_t i = 0; i < n; ++i) v[i] = v[i] + kick[i];
    }
  }
};

// 6 x 6 x 6 particles in a closed 8-spacing box, jittered and moving, under gravity: every term of the
// step is exercised (walls on all sides, the collision response, s_corr, XSPH; and vorticity
// confinement where `vorticity` > 0).
// With `skin` (pbf_skin) the whole frame's pbf_substeps steps, the lists kept from the first: each step
// is Algorithm 1 from where the last left the particles.
void ExpectAStepIsMacklinAndMullersAlgorithmOne(float vorticity, float skin = 0.0f) {
  SceneSetup scene = PbfBox({0.08f, 0.08f, 0.08f}, {0.06f, 0.06f, 0.06f}, 0.01f);
  scene.params.pbfVorticity = vorticity;
  scene.params.pbfSkin = skin;
  const int steps = skin > 0.0f ? static_cast<int>(scene.params.pbfSubsteps) : 1;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  sim::HostFluid fluid = test::DownloadFluid(*solver);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t i = 0; i < fluid.size(); ++i) {
    fluid.position[i].x += 0.1f * scene.params.spacing * u(rng);
    fluid.position[i].y += 0.1f * scene.params.spacing * u(rng);
    fluid.position[i].z += 0.1f * scene.params.spacing * u(rng);
    fluid.velocity[i] = Vec4{0.2f * u(rng), 0.2f * u(rng), 0.2f * u(rng), 0.0f};
  }
  ASSERT_TRUE(solver->Upload(fluid).ok());
  sim::HostBoundary boundary;
  solver->DownloadBoundary(&boundary);
  Reference ref{scene, boundary.position, {}, {}, {}};
  for (size_t i = 0; i < fluid.size(); ++i) {
    ref.x.push_back(Of(fluid.position[i]));
    ref.v.push_back(Of(fluid.velocity[i]));
  }
  std::unordered_map<uint32_t, size_t> index;
  for (size_t i = 0; i < fluid.size(); ++i) index[fluid.id[i]] = i;

  double dt = 0.0;
  for (int step = 0; step < steps; ++step) {
    ASSERT_TRUE(solver->Step().ok());
    dt = solver->LastStep().dt;
    EXPECT_NEAR(dt, scene.params.pbfFrame / scene.params.pbfSubsteps, 1e-9) << "a step is a frame over the substeps";
    ref.Step(dt);
  }
  const sim::HostFluid after = test::DownloadFluid(*solver);
  // Float against double: each sum of ~30 terms is good to ~1e-6 of its size; three iterations and
  // the division by dt keep the differences under 1e-4 of a spacing (and of a spacing per step) a
  // step; a step carries the last one's difference on, so a frame's steps add theirs.
  const double dx = scene.params.spacing, posTol = steps * 1e-4 * dx, velTol = posTol / dt,
               rhoTol = steps * 1e-4 * 1000.0;
  double worstX = 0, worstV = 0, moved = 0;
  for (size_t i = 0; i < after.size(); ++i) {
    const size_t r = index.at(after.id[i]);
    const D3 dxv = Of(after.position[i]) - ref.x[r], dvv = Of(after.velocity[i]) - ref.v[r];
    worstX = std::max(worstX, std::sqrt(dxv.Dot(dxv)));
    worstV = std::max(worstV, std::sqrt(dvv.Dot(dvv)));
    const D3 m = ref.x[r] - Of(fluid.position[index.at(after.id[i])]);
    moved = std::max(moved, std::sqrt(m.Dot(m)));
    EXPECT_NEAR(after.density[i], ref.density[r], rhoTol) << "particle " << after.id[i];
  }
  EXPECT_LT(worstX, posTol);
  EXPECT_LT(worstV, velTol);
  EXPECT_GT(moved, 100.0 * posTol) << "the step must move the particles for the comparison to mean anything";
}

TEST(Pbf, AStepIsMacklinAndMullersAlgorithmOne) { ExpectAStepIsMacklinAndMullersAlgorithmOne(0.0f); }

// With vorticity confinement at 1 m/s: about 20 1/s of vorticity in the random field gives dt eps |omega|
// = 0.07 m/s, a third of the velocities, against the bound velTol = 1e-4 dx / dt = 2.7e-4 m/s.
TEST(Pbf, AStepWithVorticityConfinementIsMacklinAndMullersAlgorithmOne) { ExpectAStepIsMacklinAndMullersAlgorithmOne(1.0f); }
TEST(Pbf, AFrameOfSubstepsOnListsWithASkinIsAlgorithmOneEverySubstep) {
  ExpectAStepIsMacklinAndMullersAlgorithmOne(0.0f, 0.5f);
}

// The reference's curl (the formula the stage is held to above) on a rigid rotation v = Omega x x over
// the rest lattice: omega = -(2/3) S Omega exactly, S = sum_j V r_ij^2 W'(r_ij) / r_ij, which is the
// continuum's -3 up to the lattice's quadrature (-3.06 at support 2 dx): the curl of a rotation is
// twice its angular velocity. And the confinement spins a vortex up: around a core whose vorticity
// falls off outward, N points at the core and N x omega along the flow.
TEST(PbfVorticity, TheCurlOfARotationAndTheConfinementOfAVortex) {
  const double dx = 0.01, H = 2.0 * dx, volume = dx * dx * dx;
  const Spline k{H};
  std::vector<D3> x;
  const int m = 9;  // a 9^3 lattice; the middle particle is far from its edges
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b)
      for (int c = 0; c < m; ++c) x.push_back(D3{a * dx, b * dx, c * dx});
  std::vector<std::vector<size_t>> near(x.size());
  for (size_t i = 0; i < x.size(); ++i)
    for (size_t j = 0; j < x.size(); ++j) {
      const D3 d = x[i] - x[j];
      if (j != i && d.Dot(d) < H * H) near[i].push_back(j);
    }
  const size_t centre = (m * m * m) / 2;
  const D3 c = x[centre];
  double S = 0.0;
  for (size_t j : near[centre]) {
    const D3 d = x[centre] - x[j];
    S += volume * d.Dot(k.Grad(d));
  }
  EXPECT_NEAR(-S / 3.0, 1.0, 0.03) << "the lattice's quadrature of the kernel's moment";
  const D3 omega{0.3, -0.5, 1.1};  // rad/s
  std::vector<D3> v(x.size());
  for (size_t i = 0; i < x.size(); ++i) v[i] = omega.Cross(x[i] - c);
  const D3 w = Vorticity(k, volume, x, v, near)[centre];
  const D3 expected = omega * (-2.0 / 3.0 * S);
  EXPECT_NEAR(w.x, expected.x, 1e-9);
  EXPECT_NEAR(w.y, expected.y, 1e-9);
  EXPECT_NEAR(w.z, expected.z, 1e-9);

  // A vortex about the z axis through the centre, Omega(r) = exp(-r^2 / (3 dx)^2): its vorticity peaks
  // on the axis. Every particle between one and three spacings from the axis (and two from the lattice's
  // faces) is pushed along its own velocity.
  for (size_t i = 0; i < x.size(); ++i) {
    const D3 r = x[i] - c;
    const double r2 = r.x * r.x + r.y * r.y;
    v[i] = D3{0.0, 0.0, std::exp(-r2 / (9.0 * dx * dx))}.Cross(r);
  }
  const std::vector<D3> wv = Vorticity(k, volume, x, v, near);
  const std::vector<D3> kick = Confinement(k, volume, 1.0, 1e-3, x, wv, near);
  int checked = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const D3 r = x[i] - c;
    const double radius = std::sqrt(r.x * r.x + r.y * r.y);
    const bool inner = std::min({x[i].x, x[i].y, x[i].z}) >= 2 * dx - 1e-9 &&
                       std::max({x[i].x, x[i].y, x[i].z}) <= (m - 3) * dx + 1e-9;
    if (!inner || radius < dx - 1e-9 || radius > 3 * dx + 1e-9) continue;
    ++checked;
    EXPECT_GT(kick[i].Dot(v[i]), 0.0) << "at r = " << radius / dx << " dx";
    EXPECT_LT(std::fabs(kick[i].z), 1e-9 + 1e-6 * kick[i].Length()) << "in the vortex's plane";
  }
  EXPECT_GT(checked, 20);
}

double MeanSpeed(const sim::HostFluid& f) {
  double sum = 0.0;
  for (const Vec4& v : f.velocity) sum += std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return f.size() ? sum / static_cast<double>(f.size()) : 0.0;
}

SceneSetup StillWater() { return test::PbfStillWater(0.01f); }

void RunFor(sim::Solver& solver, double seconds) {
  while (solver.Time() < seconds - 1e-9) ASSERT_TRUE(solver.Step().ok());
}

/// The pressure estimate (p / rho^2 = -Lambda / (rho0 dt^2)) against rho0 g depth in 2-cm bands over the
/// lower 80 % of the depth: within 10 % (the real-time bound).
void ExpectHydrostaticPressureBands(const sim::HostFluid& f, const SceneSetup& scene) {
  float top = 0.0f;
  for (const Vec4& x : f.position) top = std::max(top, x.y);
  const double surface = top + 0.5 * scene.params.spacing, g = 9.81, rho0 = scene.params.restDensity;
  for (double y = 0.02; y <= 0.8 * surface; y += 0.02) {
    double sum = 0.0;
    int count = 0;
    for (size_t i = 0; i < f.size(); ++i) {
      if (std::fabs(f.position[i].y - y) < 0.01) sum += f.pressure[i], ++count;
    }
    ASSERT_GT(count, 0);
    const double expected = rho0 * g * (surface - y);
    EXPECT_NEAR(sum / count, expected, 0.1 * expected) << "at y = " << y << " m";
  }
}

TEST(Pbf, StillWaterHoldsItsHydrostaticPressureAndCalms) {
  SceneSetup scene = StillWater();
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  RunFor(*solver, 1.0);
  const double speed1 = MeanSpeed(test::DownloadFluid(*solver));
  RunFor(*solver, 2.0);
  const sim::HostFluid f = test::DownloadFluid(*solver);
  ASSERT_EQ(test::FirstNonFinite(f), "");
  EXPECT_EQ(solver->GetTotals().clampedEvents, 0) << "the collision response, not the clamp, holds the water";
  // The kinetic energy the lattice's start gave is being dissipated (the solve is first order in time).
  const double speed2 = MeanSpeed(f);
  EXPECT_LT(speed2, speed1);
  ExpectHydrostaticPressureBands(f, scene);
}

// The real-time compression target (below 1 %, 1 s from the lattice) is a matter of work per
// frame: the steady compression under a column falls as 1 / (S^2 N) with S substeps of N iterations a
// frame (a Jacobi iteration carries a correction one support; bench/pbf_still_water.py measures
// S^2 N C = 94-98.5 % over seven settings here). At 6 x 4 (S^2 N = 144) the water holds its depth within
// the target. Its pressure estimate reads rho0 g depth within the 10 % band when s_corr is off; with it,
// the upper bands read 10-15 % low at 6 x 4 (0-5 % at 3 x 3): s_corr's push is the same each iteration
// whatever dt is, so at more iterations of a shorter step it carries more of the top layers' weight, and
// the estimate (from lambda alone) does not count it.
TEST(Pbf, StillWaterMeetsTheCompressionTargetWithSixSubstepsOfFourIterations) {
  for (const float k : {0.1f, 0.0f}) {
    SceneSetup scene = StillWater();
    scene.params.pbfSubsteps = 6.0f;
    scene.params.pbfIterations = 4.0f;
    scene.params.pbfCorrK = k;
    auto solver = test::CreateOrFail(scene);
    ASSERT_TRUE(solver);
    RunFor(*solver, 1.0);
    const sim::HostFluid f = test::DownloadFluid(*solver);
    ASSERT_EQ(test::FirstNonFinite(f), "");
    EXPECT_LT(solver->LastStep().meanDensityError, 0.01f) << "pbf_corr_k " << k;
    if (k == 0.0f) ExpectHydrostaticPressureBands(f, scene);
  }
}

// The start-up warning predicts the rest compression from the law above (K (1 + eps) g D dt^2 / (N s^2),
// K from the 1-cm tank) and names the substeps that bring it to about 2 %. At 5 mm the same tank at the
// defaults' 3 substeps is predicted at 14 % (measured: the water blows up, 98 % mean compression at 0.9 s);
// at 1 cm, 3.5 % (measured 3.49 %), below the 5 % that warns.
TEST(Pbf, AColumnTooDeepForItsSubstepsIsNamedAtStartUp) {
  {
    test::LogCapture log;
    sim::WarnAboutSettings(test::PbfStillWater(0.005f), 32000, 0.0f);
    EXPECT_EQ(log.Count("pbf: expect about 14% mean compression at rest under the 0.2 m column", LogLevel::kWarn), 1)
        << log.All();
    EXPECT_EQ(log.Count("pbf_substeps 8 would give about 2 %", LogLevel::kWarn), 1) << log.All();
  }
  test::LogCapture log;
  sim::WarnAboutSettings(StillWater(), 4000, 0.0f);
  EXPECT_EQ(log.Count("pbf: expect"), 0) << log.All();
}

// The still-water targets (docs/design/pbf.md) at the defaults (3 substeps of 3 iterations a 90 Hz frame): not met,
// and neither can be bought without undoing what the defaults are for. Measured (bench/pbf_still_water.py,
// bench/results/pbf_still_water.csv): mean compression 3.5 % at 1 s (below 1 % needs S^2 N >= 100, twice
// the frame's cost, which is already twice the real-time budget); mean speed 9.9 mm/s at 1 s (4.2 at 2 s),
// 8.9-10.1 mm/s at every S x N, so the solve is not what keeps it moving: the lattice's settling, damped
// by XSPH alone. c = 0.1 calms it to 4.6 mm/s but takes a third of stirred water's kinetic energy
// (13.5 against 20.3 mJ/kg after 4 s of `stir`; WCSPH 20.2). docs/design/pbf.md.
TEST(Pbf, DISABLED_StillWaterMeetsTheRealTimeTargets) {
  SceneSetup scene = StillWater();
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  RunFor(*solver, 1.0);
  EXPECT_LT(MeanSpeed(test::DownloadFluid(*solver)), 0.005);
  EXPECT_LT(solver->LastStep().meanDensityError, 0.01f);
}

// 1 and 20 iterations on a dam break (1 s): no NaN, nothing lost or clamped, and no particle faster
// than the column's free fall from its top, sqrt(2 g H), with a factor 2 for the splash.
class PbfIterations : public ::testing::TestWithParam<int> {};

TEST_P(PbfIterations, ADamBreakStaysStable) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.method = sim::SolverMethod::kPbf;
  scene.params.pbfIterations = static_cast<float>(GetParam());
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const int count = solver->FluidCount();
  const double bound = 2.0 * std::sqrt(2.0 * 9.81 * 0.15);
  while (solver->Time() < 1.0) {
    ASSERT_TRUE(solver->Step().ok());
    ASSERT_LT(solver->LastStep().maxSpeed, bound) << "at t = " << solver->Time() << " s";
  }
  const sim::HostFluid f = test::DownloadFluid(*solver);
  EXPECT_EQ(test::FirstNonFinite(f), "");
  EXPECT_EQ(static_cast<int>(f.size()), count);
  EXPECT_EQ(solver->GetTotals().clampedEvents, 0);
}

INSTANTIATE_TEST_SUITE_P(Extremes, PbfIterations, ::testing::Values(1, 20));

// The speed cap (pbf_max_speed, a safety net) holds after every change of the velocity in a step, not
// only the prediction's and the finish's: vorticity confinement at 10 m/s spun a dam break up to 63.5
// m/s against the cap of 20, and to 938 m/s with a frame of 0.1 s; XSPH at its largest adds to it.
struct CapCase {
  float frame, vorticity, xsph;
};
class PbfSpeedCap : public ::testing::TestWithParam<CapCase> {};

TEST_P(PbfSpeedCap, HoldsAfterEveryVelocityChange) {
  SceneSetup scene = test::SmallDamBreak(0.01f);
  scene.method = sim::SolverMethod::kPbf;
  scene.params.pbfFrame = GetParam().frame;
  scene.params.pbfVorticity = GetParam().vorticity;
  scene.params.pbfXsph = GetParam().xsph;
  auto solver = test::CreateOrFail(scene);
  ASSERT_TRUE(solver);
  const float cap = scene.params.pbfMaxSpeed;
  float fastest = 0.0f;
  for (int k = 0; k < 200 && solver->Time() < 2.0; ++k) {
    ASSERT_TRUE(solver->Step().ok());
    const sim::HostFluid f = test::DownloadFluid(*solver);
    for (const Vec4& v : f.velocity) fastest = std::max(fastest, std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z));
    ASSERT_LE(fastest, cap * (1.0f + 1e-5f)) << "after step " << k + 1 << ", t = " << solver->Time() << " s";
  }
}

INSTANTIATE_TEST_SUITE_P(Extremes, PbfSpeedCap,
                         ::testing::Values(CapCase{1.0f / 90.0f, 10.0f, 0.0f}, CapCase{0.1f, 10.0f, 0.0f},
                                           CapCase{0.1f, 10.0f, 1.0f}, CapCase{0.1f, 0.0f, 1.0f}));

}  // namespace
}  // namespace sphxr
