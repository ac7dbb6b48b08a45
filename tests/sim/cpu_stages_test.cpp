// The CPU backend's SIMD stages (sim/src/cpu/) against the per-particle stages of stages.h (the
// CUDA backend's) and against brute-force O(n^2) sums in double. Density blocks: the same neighbour
// lists in the same order, the same densities to float rounding, on random, clustered, cell-border and
// over-full sets (more than kLanes particles in a cell, more neighbours than list slots), with and without
// reuse masking some particles out, and with walls (their kernel sums). Forces: the neighbour-list sum
// and the wall terms (mirrored and wall density). Wall pressure: the blocks of 16 wall particles.
// Position-based fluids: the lambda, correction and XSPH passes (solvers/pbf/pbf_simd.h).
// Reuse's crowding (CellCountStage, CellBoxSumStage, ActivityStage; both backends' stages) against counting by brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "cpu/stages.h"
#include "solvers/dfsph/dfsph_simd.h"
#include "solvers/pbf/pbf_simd.h"
#include "stages/integrate.h"
#include "morton.h"

namespace sphxr::sim {
namespace {

constexpr float kSpacing = 0.01f;
constexpr float kSupport = 2.0f * kSpacing;

/// The Morton key of p's cell, as CellCodeStage computes it.
uint32_t CellKey(const GridView& g, Vec3 p) {
  int cx, cy, cz;
  g.CellOf(p, &cx, &cy, &cz);
  return MortonEncode(static_cast<uint32_t>(cx), static_cast<uint32_t>(cy), static_cast<uint32_t>(cz));
}

/// The points in Morton order of their cells, stably (as the backend sorts particles).
std::vector<Vec3> SortedByCell(const GridView& g, const std::vector<Vec3>& points) {
  std::vector<std::pair<uint32_t, Vec3>> keyed;
  for (const Vec3& p : points) keyed.push_back({CellKey(g, p), p});
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Vec3> out;
  for (const auto& k : keyed) out.push_back(k.second);
  return out;
}

/// Particles sorted by cell (Morton order, as the backend sorts them) with their grid, fields and
/// neighbour lists in host vectors; Run*() evaluates one traversal into them.
struct Setup {
  Physics ph{};
  int nx = 0, ny = 0, nz = 0;
  Vec3 origin{0.0f, 0.0f, 0.0f};
  std::vector<Vec4> position, velocity, acceleration;
  std::vector<float> density, pressure, pressureTerm;
  std::vector<int32_t> idle;
  std::vector<uint32_t> start, end, index, count;
  std::vector<uint8_t> boundaryNear;
  std::vector<Vec4> boundary;  // sorted by cell, w = Psi_b
  std::vector<float> boundaryAlpha, boundaryInvReference, boundaryPressureTerm;
  std::vector<uint32_t> boundaryStart, boundaryEnd;

  Setup(std::vector<Vec3> points, int maxNeighbours, std::vector<Vec3> walls = {}) {
    ph.kernel = CubicSpline::Make(kSupport);
    ph.mass = 1000.0f * kSpacing * kSpacing * kSpacing;
    ph.restDensity = 1000.0f;
    ph.invRestDensity = 1.0f / 1000.0f;
    ph.stiffness = 50000.0f;
    ph.exponent = 7.0f;
    ph.maxNeighbours = maxNeighbours;
    ph.smoothing = 0.5f * kSupport;
    ph.alpha = 0.3f;
    ph.soundSpeed = std::sqrt(50000.0f * 7.0f / 1000.0f);
    ph.gravity = Vec3{0.0f, 0.0f, 0.0f};
    ph.boundaryGradScale = 1.0f;
    ph.wallDensity = false;  // mirrored walls: the force stage needs the Shepard pressure average
    nx = 9;  // 0.18 x 0.16 x 0.16 m of 0.02 m cells: an odd row, whose last cell has no pair
    ny = nz = 8;
    GridView g = Grid();
    for (const Vec3& p : SortedByCell(g, points)) position.push_back(Vec4{p.x, p.y, p.z, 0.0f});
    const size_t n = position.size();
    std::mt19937 rng(17);  // velocities of about 1 m/s in every direction: both signs of v_ij . x_ij
    std::uniform_real_distribution<float> uv(-1.0f, 1.0f);
    for (size_t i = 0; i < n; ++i) velocity.push_back(Vec4{uv(rng), uv(rng), uv(rng), 0.0f});
    acceleration.assign(n, Vec4{0.0f, 0.0f, 0.0f, 0.0f});
    density.assign(n, -1.0f);
    pressure.assign(n, -1.0f);
    pressureTerm.assign(n, -1.0f);
    idle.assign(n, -1);
    index.assign(n * static_cast<size_t>(maxNeighbours), 0xdeadbeefu);
    count.assign(n, 0xdeadbeefu);
    const size_t cells = static_cast<size_t>(nx) * ny * nz;
    start.assign(cells, kEmptyCell);
    end.assign(cells, kEmptyCell);
    boundaryNear.assign(cells, 0);
    boundaryStart.assign(cells, kEmptyCell);
    boundaryEnd.assign(cells, kEmptyCell);
    g = Grid();
    const std::vector<Vec3> sortedWalls = SortedByCell(g, walls);
    const float psi = 0.7f * 1000.0f * kSpacing * kSpacing * kSpacing;
    for (size_t b = 0; b < sortedWalls.size(); ++b) {
      const Vec3 p = sortedWalls[b];
      boundary.push_back(Vec4{p.x, p.y, p.z, psi});
      boundaryAlpha.push_back(0.3f);
      // Wall density's inputs: a reference sum near the rest lattice's, and a p_b/rho_b^2 of either sign
      // of difference from the fluid's (WallPressureStage's output, for the force stage).
      // (The rest lattice's sum beside a flat wall is about half of 1 / spacing^3.)
      boundaryInvReference.push_back(1.0f / ((0.45f + 0.02f * static_cast<float>(b % 7)) / (kSpacing * kSpacing * kSpacing)));
      boundaryPressureTerm.push_back(1e-3f * static_cast<float>(b % 5));
      int cx, cy, cz;
      g.CellOf(p, &cx, &cy, &cz);
      const uint32_t c = g.Linear(cx, cy, cz);
      if (boundaryStart[c] == kEmptyCell) boundaryStart[c] = static_cast<uint32_t>(b);
      boundaryEnd[c] = static_cast<uint32_t>(b + 1);
    }
    g = Grid();
    for (size_t c = 0; c < cells; ++c) boundaryNear[c] = AnyInNeighbourCells(g, boundaryStart.data(), static_cast<int>(c)) ? 1 : 0;
    for (size_t i = 0; i < n; ++i) {
      int cx, cy, cz;
      g.CellOf(Xyz(position[i]), &cx, &cy, &cz);
      const uint32_t c = g.Linear(cx, cy, cz);
      if (start[c] == kEmptyCell) start[c] = static_cast<uint32_t>(i);
      end[c] = static_cast<uint32_t>(i + 1);
    }
  }

  GridView Grid() {
    GridView g{};
    g.origin = origin;
    g.cellSize = kSupport;
    g.invCellSize = 1.0f / kSupport;
    g.nx = nx;
    g.ny = ny;
    g.nz = nz;
    g.fluidStart = start.data();
    g.fluidEnd = end.data();
    g.boundaryNear = boundaryNear.data();
    g.boundaryStart = boundaryStart.data();
    g.boundaryEnd = boundaryEnd.data();
    g.boundary = boundary.data();
    g.boundaryAlpha = boundaryAlpha.data();
    g.boundaryInvReference = boundaryInvReference.data();
    g.boundaryPressureTerm = boundaryPressureTerm.data();
    g.bodyCount = 0;
    return g;
  }

  DensityStage Stage() {
    FluidView f{};
    f.position = position.data();
    f.velocity = velocity.data();
    f.acceleration = acceleration.data();
    f.density = density.data();
    f.pressure = pressure.data();
    f.pressureTerm = pressureTerm.data();
    f.idle = idle.data();
    f.count = static_cast<int>(position.size());
    return DensityStage{Grid(), f, NeighbourList{index.data(), count.data(), ph.maxNeighbours}, ph};
  }

  ForceStage Forces() {
    const DensityStage d = Stage();
    return ForceStage{d.grid, d.fluid, d.list, ph, nullptr};
  }

  void RunPerParticle(bool reuse, int idleSteps) {
    const DensityStage s = Stage();
    const ComputesThisStep computes{idle.data(), idleSteps};
    for (int i = 0; i < static_cast<int>(position.size()); ++i) {
      if (!reuse || computes(i)) s(i);
    }
  }

  /// The sorted Morton keys, as the backend's sort leaves them.
  std::vector<uint32_t> Keys() {
    const GridView g = Grid();
    std::vector<uint32_t> keys;
    for (const Vec4& p : position) keys.push_back(CellKey(g, Xyz(p)));
    return keys;
  }

  /// The first particle of each density block (DensityBlockStart).
  std::vector<uint32_t> BlockStarts(const std::vector<uint32_t>& keys, bool pairsOnly) {
    return BlockStarts(BlockSet{keys.data(), static_cast<int>(keys.size())}, pairsOnly);
  }

  /// The backend's set with reuse (cpu/blocks.h BlockSet): the particles that compute this step, their
  /// keys, and each particle's rank among them (n + 1 values), held in `compactList`, `compactKeys` and
  /// `compactRank`.
  BlockSet ComputingSet(const std::vector<uint32_t>& keys, int idleSteps) {
    const int n = static_cast<int>(position.size());
    const ComputesThisStep computes{idle.data(), idleSteps};
    compactList.clear();
    compactKeys.clear();
    compactRank.assign(1, 0u);
    for (int i = 0; i < n; ++i) {
      if (computes(i)) {
        compactList.push_back(static_cast<uint32_t>(i));
        compactKeys.push_back(keys[i]);
      }
      compactRank.push_back(static_cast<uint32_t>(compactList.size()));
    }
    return BlockSet{compactKeys.data(), static_cast<int>(compactKeys.size()), compactList.data(), compactRank.data()};
  }
  std::vector<uint32_t> compactList, compactKeys, compactRank;

  /// The first entry of each density block of `set`.
  std::vector<uint32_t> BlockStarts(const BlockSet& set, bool pairsOnly) {
    const DensityBlockStart isStart{Grid(), set, pairsOnly};
    std::vector<uint32_t> blocks;
    for (int e = 0; e < set.count; ++e) {
      if (isStart(e)) blocks.push_back(static_cast<uint32_t>(e));
    }
    return blocks;
  }

  /// The density blocks drawn from the particles that compute only, as the backend runs them with reuse.
  void RunCompacted(int idleSteps) {
    const std::vector<uint32_t> keys = Keys();
    const BlockSet set = ComputingSet(keys, idleSteps);
    const std::vector<uint32_t> blocks = BlockStarts(set, false);
    const DensityBlockStage s{Stage(), set, blocks.data(), nullptr, idleSteps, false};
    for (int b = 0; b < static_cast<int>(blocks.size()); ++b) s(b);
  }

  void RunBlocked(bool reuse, int idleSteps, bool pairsOnly = false) {
    const std::vector<uint32_t> keys = Keys();
    const std::vector<uint32_t> blocks = BlockStarts(keys, pairsOnly);
    const DensityBlockStage s{Stage(), BlockSet{keys.data(), static_cast<int>(keys.size())}, blocks.data(),
                              reuse ? idle.data() : nullptr, idleSteps, pairsOnly};
    for (int b = 0; b < static_cast<int>(blocks.size()); ++b) s(b);
  }
};

/// Runs both traversals on copies of one set and compares them with each other and with brute force.
void Compare(const std::vector<Vec3>& points, int maxNeighbours, const std::string& what, bool reuse = false,
             const std::vector<Vec3>& walls = {}) {
  SCOPED_TRACE(what);
  Setup perParticle(points, maxNeighbours, walls), blocked(points, maxNeighbours, walls),
      pairs(points, maxNeighbours, walls), compacted(points, maxNeighbours, walls);
  const size_t n = perParticle.position.size();
  constexpr int kIdle = 3;
  if (reuse) {  // every third particle reuses this step (IC = 1), every fifth computes at IC = IDLE
    for (size_t i = 0; i < n; ++i) {
      const int32_t ic = i % 3 == 0 ? 1 : (i % 5 == 0 ? kIdle : -1);
      perParticle.idle[i] = blocked.idle[i] = pairs.idle[i] = compacted.idle[i] = ic;
    }
  }
  perParticle.RunPerParticle(reuse, kIdle);
  blocked.RunBlocked(reuse, kIdle);
  pairs.RunBlocked(reuse, kIdle, /*pairsOnly=*/true);
  if (reuse) compacted.RunCompacted(kIdle);
  // The boxes, the pairs-only layout and (with reuse) the boxes of the computing particles alone give
  // every lane the same candidates in the same order: the same bits, not just close.
  std::vector<const Setup*> others = {&pairs};
  if (reuse) others.push_back(&compacted);
  for (const Setup* other : others) {
    const char* which = other == &pairs ? "pairs only, lanes masked" : "boxes of the computing particles";
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(blocked.count[i], other->count[i]) << "particle " << i << ", " << which;
      ASSERT_EQ(std::memcmp(&blocked.density[i], &other->density[i], sizeof(float)), 0)
          << "particle " << i << ": " << blocked.density[i] << " against " << other->density[i] << " (" << which << ")";
      ASSERT_EQ(std::memcmp(&blocked.pressure[i], &other->pressure[i], sizeof(float)), 0) << "particle " << i << ", " << which;
      ASSERT_EQ(std::memcmp(&blocked.position[i].w, &other->position[i].w, sizeof(float)), 0)
          << "particle " << i << ", " << which;
    }
    ASSERT_EQ(blocked.index, other->index) << which;
  }
  const CubicSpline k = perParticle.ph.kernel;
  size_t overflowed = 0, checked = 0, nearWall = 0;
  for (size_t i = 0; i < n; ++i) {
    const bool computes = !reuse || perParticle.idle[i] < 0 || perParticle.idle[i] == kIdle;
    if (!computes) {  // untouched by both
      EXPECT_EQ(blocked.density[i], -1.0f) << "particle " << i;
      EXPECT_EQ(blocked.count[i], 0xdeadbeefu) << "particle " << i;
      continue;
    }
    ++checked;
    // The same neighbour list, in the same order.
    ASSERT_EQ(blocked.count[i], perParticle.count[i]) << "particle " << i;
    const size_t stored = std::min<size_t>(blocked.count[i], static_cast<size_t>(maxNeighbours));
    if (blocked.count[i] > static_cast<uint32_t>(maxNeighbours)) ++overflowed;
    for (size_t s = 0; s < stored; ++s) {
      ASSERT_EQ(blocked.index[i * maxNeighbours + s], perParticle.index[i * maxNeighbours + s])
          << "particle " << i << " slot " << s;
    }
    // Brute force: every particle within the support (self included), in double.
    const Vec3 xi = Xyz(blocked.position[i]);
    double sum = 0.0;
    uint32_t neighbours = 0;
    bool borderline = false;  // a pair within float rounding of the support: its count is the float test's
    for (size_t j = 0; j < n; ++j) {
      const Vec3 d = xi - Xyz(blocked.position[j]);
      const double r = std::sqrt(static_cast<double>(d.x) * d.x + static_cast<double>(d.y) * d.y +
                                 static_cast<double>(d.z) * d.z);
      if (std::abs(r - k.H) < 1e-5 * k.H) borderline = true;
      if (r < k.H) {
        const double q = r / k.H;
        sum += q <= 0.5 ? k.sigma * (6.0 * (q * q * q - q * q) + 1.0) : k.sigma * 2.0 * std::pow(1.0 - q, 3);
        if (j != i) ++neighbours;
      }
    }
    if (!borderline) {
      EXPECT_EQ(blocked.count[i], neighbours) << "particle " << i;
    }
    double wallSum = 0.0;  // sum_b Psi_b W_ib
    for (const Vec4& b : blocked.boundary) {
      const Vec3 d = xi - Xyz(b);
      const double r = std::sqrt(static_cast<double>(d.x) * d.x + static_cast<double>(d.y) * d.y +
                                 static_cast<double>(d.z) * d.z);
      if (r < k.H) {
        const double q = r / k.H;
        wallSum += b.w * (q <= 0.5 ? k.sigma * (6.0 * (q * q * q - q * q) + 1.0) : k.sigma * 2.0 * std::pow(1.0 - q, 3));
      }
    }
    if (wallSum > 0.0) ++nearWall;
    EXPECT_EQ(blocked.position[i].w, perParticle.position[i].w) << "particle " << i << ": the near-wall flag";
    const double brute = perParticle.ph.mass * sum + wallSum;
    EXPECT_NEAR(blocked.density[i], brute, 1e-5 * brute) << "particle " << i;
    // Each particle's sum adds the same terms in the same order; only a fused multiply-add in the
    // kernel's polynomial may round one term differently.
    EXPECT_NEAR(blocked.density[i], perParticle.density[i], 1e-6f * perParticle.density[i]) << "particle " << i;
    // The pressure B((rho/rho0)^gamma - 1) carries the densities' difference (and one more rounding of
    // rho) through dp/drho = gamma B (rho/rho0)^(gamma-1) / rho0: near rest one float ulp of rho is
    // 7 x 5e4 x 1.2e-7 = 0.04 Pa, whatever p is. Plus the rounding of p's own evaluation.
    {
      const Physics& ph = perParticle.ph;
      const double ratio = perParticle.density[i] / ph.restDensity;
      const double slope = ph.exponent * ph.stiffness * std::pow(ratio, ph.exponent - 1.0) / ph.restDensity;
      const double eps = std::numeric_limits<float>::epsilon();
      const double drho = std::fabs(double(blocked.density[i]) - perParticle.density[i]) + eps * perParticle.density[i];
      const double margin = slope * drho + 4.0 * eps * (std::fabs(perParticle.pressure[i]) + ph.stiffness * eps);
      EXPECT_NEAR(blocked.pressure[i], perParticle.pressure[i], margin) << "particle " << i;
    }
  }
  EXPECT_GT(checked, n / 3);
  if (maxNeighbours < 30) {
    EXPECT_GT(overflowed, 0u) << "the over-full case must overflow the list";
  }
  if (!walls.empty()) {
    EXPECT_GT(nearWall, checked / 5) << "the wall case must put particles near the walls";
    EXPECT_LT(nearWall, checked) << "the wall case must leave particles away from the walls (lanes masked off)";
  }
}

/// Wall particles: a floor sheet at the rest spacing, a side wall, and a denser patch of floor whose
/// cells hold more than 16 wall particles (several lane blocks per cell); water 6 spacings deep over
/// them, slightly compressed (so some wall particles see pressure and some none).
struct WallScene {
  std::vector<Vec3> walls, water;
  WallScene() {
    for (int z = 0; z < 16; ++z)
      for (int x = 0; x < 18; ++x) {
        walls.push_back(Vec3{(x + 0.5f) * kSpacing, 0.002f, (z + 0.5f) * kSpacing});
        for (int y = 0; y < 6; ++y) {
          water.push_back(Vec3{(x + 0.5f) * kSpacing + 0.0005f * static_cast<float>(y % 2), 0.0075f + y * 0.0098f,
                               (z + 0.5f) * kSpacing});
        }
      }
    for (int z = 0; z < 16; ++z)
      for (int y = 0; y < 8; ++y) walls.push_back(Vec3{0.001f, (y + 0.5f) * kSpacing, (z + 0.5f) * kSpacing});
    for (int z = 0; z < 10; ++z)
      for (int x = 0; x < 10; ++x) walls.push_back(Vec3{0.04f + x * 0.004f, 0.0005f, 0.04f + z * 0.004f});
  }
};

std::vector<Vec3> Random(size_t n, float lo, float hi, unsigned seed, float hiX = 0.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi), ux(lo, hiX > 0.0f ? hiX : hi);
  std::vector<Vec3> p(n);
  for (Vec3& v : p) v = Vec3{ux(rng), u(rng), u(rng)};
  return p;
}

/// 2,000 points in a Gaussian cluster (sigma 8 mm) at the grid's middle: lists that overflow 24 slots.
std::vector<Vec3> Clustered() {
  std::mt19937 rng(7);
  std::normal_distribution<float> nd(0.0f, 0.008f);
  std::vector<Vec3> p;
  for (int i = 0; i < 2000; ++i) {
    p.push_back(Vec3{std::clamp(0.08f + nd(rng), 0.0f, 0.179f), std::clamp(0.08f + nd(rng), 0.0f, 0.159f),
                     std::clamp(0.08f + nd(rng), 0.0f, 0.159f)});
  }
  return p;
}

/// ForceListStage against ForceStage and against the pair terms summed in double, on the densities
/// and lists the blocked density stage left (no gravity; the particles away from walls against the
/// fluid pair terms alone in double, those near walls against ForceStage only).
void CompareForces(const std::vector<Vec3>& points, int maxNeighbours, const std::string& what,
                   const std::vector<Vec3>& walls = {}, bool wallDensity = false) {
  SCOPED_TRACE(what);
  Setup s(points, maxNeighbours, walls);
  s.ph.wallDensity = wallDensity;
  s.RunBlocked(false, 0);
  const size_t n = s.position.size();
  const ForceStage perParticle = s.Forces();
  const ForceListStage simd{s.Forces()};
  std::vector<Vec4> reference(n);
  for (size_t i = 0; i < n; ++i) perParticle(static_cast<int>(i));
  reference = s.acceleration;
  std::fill(s.acceleration.begin(), s.acceleration.end(), Vec4{9.0f, 9.0f, 9.0f, 9.0f});
  for (size_t i = 0; i < n; ++i) simd(static_cast<int>(i));
  const Physics& ph = s.ph;
  const CubicSpline k = ph.kernel;
  const double h = ph.smoothing, eps = 0.01 * h * h, viscFluid = 2.0 * ph.alpha * ph.soundSpeed * h;
  size_t overflowed = 0, nearWall = 0;
  for (size_t i = 0; i < n; ++i) {
    if (s.count[i] > static_cast<uint32_t>(maxNeighbours)) ++overflowed;
    if (s.position[i].w != 0.0f) {  // walls in the support: the wall term (and its Shepard average) too
      ++nearWall;
      const double scale = std::abs(reference[i].x) + std::abs(reference[i].y) + std::abs(reference[i].z);
      EXPECT_NEAR(s.acceleration[i].x, reference[i].x, 1e-5 * scale + 1e-6) << "particle " << i;
      EXPECT_NEAR(s.acceleration[i].y, reference[i].y, 1e-5 * scale + 1e-6) << "particle " << i;
      EXPECT_NEAR(s.acceleration[i].z, reference[i].z, 1e-5 * scale + 1e-6) << "particle " << i;
      continue;
    }
    double a[3] = {0, 0, 0}, scale = 0.0;  // scale: the sum of the pair terms' magnitudes
    for (size_t j = 0; j < n; ++j) {
      const double d[3] = {static_cast<double>(s.position[i].x) - s.position[j].x,
                           static_cast<double>(s.position[i].y) - s.position[j].y,
                           static_cast<double>(s.position[i].z) - s.position[j].z};
      const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (r >= k.H || r == 0.0) continue;
      const double q = r / k.H;
      const double grad = q <= 0.5 ? k.gradA * (3.0 * q - 2.0) : -k.gradB * (1.0 - q) * (1.0 - q) / r;
      double term = static_cast<double>(s.pressureTerm[i]) + s.pressureTerm[j];
      const double vx = (static_cast<double>(s.velocity[i].x) - s.velocity[j].x) * d[0] +
                        (static_cast<double>(s.velocity[i].y) - s.velocity[j].y) * d[1] +
                        (static_cast<double>(s.velocity[i].z) - s.velocity[j].z) * d[2];
      if (vx < 0.0) term -= viscFluid * vx / ((r * r + eps) * (static_cast<double>(s.density[i]) + s.density[j]));
      for (int c = 0; c < 3; ++c) a[c] -= d[c] * ph.mass * term * grad;
      scale += std::abs(ph.mass * term * grad) * r;
    }
    const float got[3] = {s.acceleration[i].x, s.acceleration[i].y, s.acceleration[i].z};
    const float ref[3] = {reference[i].x, reference[i].y, reference[i].z};
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(got[c], a[c], 1e-5 * scale + 1e-6) << "particle " << i << " axis " << c;
      EXPECT_NEAR(got[c], ref[c], 1e-5 * scale + 1e-6) << "particle " << i << " axis " << c;
    }
  }
  if (maxNeighbours < 30) {
    EXPECT_GT(overflowed, 0u) << "the over-full case must overflow the list";
  }
  if (!walls.empty()) {
    EXPECT_GT(nearWall, n / 10) << "the wall case must put particles near the wall";
  }
}

TEST(CpuStages, ForcesNearMirroredWallsMatchPerParticle) {
  // A floor of wall particles under water 6 spacings deep: the Shepard pressure average feeds the wall.
  std::vector<Vec3> walls, water;
  for (int z = 0; z < 16; ++z)
    for (int x = 0; x < 18; ++x) {
      walls.push_back(Vec3{(x + 0.5f) * kSpacing, 0.002f, (z + 0.5f) * kSpacing});
      for (int y = 0; y < 6; ++y) water.push_back(Vec3{(x + 0.5f) * kSpacing, 0.0075f + y * 0.0098f, (z + 0.5f) * kSpacing});
    }
  CompareForces(water, 64, "mirrored floor", walls);
}

TEST(CpuStages, ForcesNearWallsWithTheirOwnDensityMatchPerParticle) {
  // Wall density: each wall particle's own p_b/rho_b^2 in the pair term; a floor, a side wall and a
  // dense patch (more wall candidates than one batch of kLanes per particle).
  const WallScene scene;
  CompareForces(scene.water, 64, "wall density", scene.walls, /*wallDensity=*/true);
  CompareForces(scene.water, 64, "mirrored, side wall and dense patch", scene.walls);
}

TEST(CpuStages, DensityNearWallsMatchesPerParticleAndBruteForce) {
  const WallScene scene;
  Compare(scene.water, 64, "walls", /*reuse=*/false, scene.walls);
  Compare(scene.water, 64, "walls, reuse", /*reuse=*/true, scene.walls);
  // Random water over the walls: blocks whose two cells differ in having walls around.
  Compare(Random(3000, 0.0f, 0.16f, 8, 0.18f), 64, "random over walls", /*reuse=*/false, scene.walls);
}

TEST(CpuStages, WallPressureBlocksMatchPerCellAndBruteForce) {
  const WallScene scene;
  struct Setup s(scene.water, 64, scene.walls);
  s.ph.wallDensity = true;
  std::vector<uint32_t> wallCells;
  size_t fullest = 0;
  for (size_t c = 0; c < s.boundaryStart.size(); ++c) {
    if (s.boundaryStart[c] == kEmptyCell) continue;
    wallCells.push_back(static_cast<uint32_t>(c));
    fullest = std::max<size_t>(fullest, s.boundaryEnd[c] - s.boundaryStart[c]);
  }
  ASSERT_GT(fullest, static_cast<size_t>(kLanes)) << "a cell must hold more wall particles than one block";
  const size_t nb = s.boundary.size();
  std::vector<float> perCell(nb, -1.0f), blocked(nb, -1.0f);
  const DensityStage d = s.Stage();
  const WallPressureStage scalar{d.grid, d.fluid, s.ph, wallCells.data(), perCell.data()};
  const WallPressureBlockStage simd{WallPressureStage{d.grid, d.fluid, s.ph, wallCells.data(), blocked.data()}};
  for (int c = 0; c < static_cast<int>(wallCells.size()); ++c) {
    scalar(c);
    simd(c);
  }
  const CubicSpline k = s.ph.kernel;
  size_t pressed = 0;
  for (size_t b = 0; b < nb; ++b) {
    double sum = 0.0;  // brute force: every fluid particle, in double
    for (const Vec4& f : s.position) {
      const Vec3 dx = Xyz(s.boundary[b]) - Xyz(f);
      const double r = std::sqrt(static_cast<double>(dx.x) * dx.x + static_cast<double>(dx.y) * dx.y +
                                 static_cast<double>(dx.z) * dx.z);
      if (r < k.H) {
        const double q = r / k.H;
        sum += q <= 0.5 ? k.sigma * (6.0 * (q * q * q - q * q) + 1.0) : k.sigma * 2.0 * std::pow(1.0 - q, 3);
      }
    }
    const double rho = s.ph.restDensity * sum * s.boundaryInvReference[b];
    const double p = std::max(0.0, s.ph.stiffness * (std::pow(rho / s.ph.restDensity, 7.0) - 1.0));
    const double expected = p > 0.0 ? p / (rho * rho) : 0.0;
    if (expected > 0.0) ++pressed;
    // The same terms in the same order; a fused multiply-add in the kernel may round one differently.
    // Near rest p = B((rho/rho0)^7 - 1) turns a rounding of rho into 7 B / rho0 times as much pressure
    // (relative to p, a thousand times more): so the bound is rho's float rounding (1e-6 of it, a sum
    // of some 30 terms) carried through dp/drho, over rho^2.
    const double rho0 = s.ph.restDensity;
    const double rounding = 1e-6 * 7.0 * s.ph.stiffness / (rho0 * rho0);
    EXPECT_NEAR(blocked[b], perCell[b], rounding) << "wall particle " << b;
    EXPECT_NEAR(blocked[b], expected, rounding + 1e-4 * expected) << "wall particle " << b;
  }
  EXPECT_GT(pressed, nb / 10) << "some wall particles must carry pressure";
  EXPECT_LT(pressed, nb) << "and some none (no fluid near, or the water not compressed there)";
}

TEST(CpuStages, ForcesMatchPerParticleAndBruteForce) {
  CompareForces(Random(3000, 0.0f, 0.16f, 6, 0.18f), 64, "random");
}

TEST(CpuStages, ForcesOfOverflowingListsMatch) {
  CompareForces(Clustered(), 24, "clustered, lists overflowing");
}

/// Position-based fluids' three neighbour passes (solvers/pbf/pbf_simd.h) against the per-particle stages
/// (solvers/pbf/pbf_stages.h) and against the pass's sums in double over every fluid and wall particle: the
/// density and lambda, the position correction (with the artificial pressure s_corr), XSPH.
void ComparePbf(const std::vector<Vec3>& points, int maxNeighbours, const std::string& what,
                const std::vector<Vec3>& walls = {}) {
  SCOPED_TRACE(what);
  Setup s(points, maxNeighbours, walls);
  Physics& ph = s.ph;
  ph.volume = kSpacing * kSpacing * kSpacing;
  PbfConstants pbf{};
  pbf.relaxation = 1.0f / (kSpacing * kSpacing);  // eps of the order of sum |grad C|^2 (units 1/m^2)
  pbf.corrK = 0.1f;
  pbf.corrN = 4;
  pbf.invCorrW = 1.0f / ph.kernel.W(0.2f * kSupport);
  pbf.xsph = 0.01f;
  s.RunBlocked(false, 0);  // the neighbour lists
  const size_t n = s.position.size();
  const ForceStage f = s.Forces();
  std::vector<float> lambda(n, 0.0f), lambdaSum(n, 0.0f), lambdaRef(n), densityRef(n);
  std::vector<Vec4> delta(n), deltaRef(n), boundaryGrad(n), own(n);
  // The SIMD lambda pass fills the pair cache (as on the CPU backend), which the SIMD correction reads;
  // the scalar stages recompute the pairs.
  const int stride = PairCacheStride(maxNeighbours);
  std::vector<float> pairGrad(n * static_cast<size_t>(stride), std::numeric_limits<float>::quiet_NaN());
  const PbfView view{lambda.data(), lambdaSum.data(), delta.data(), boundaryGrad.data(), pairGrad.data(), own.data(), stride};
  const PbfLambdaStage lambdaStage{f.grid, f.fluid, f.list, ph, pbf, view};
  const CubicSpline k = ph.kernel;
  const double invRho0 = ph.invRestDensity;
  // 1. lambda
  for (size_t i = 0; i < n; ++i) lambdaStage(static_cast<int>(i));
  lambdaRef = lambda;
  densityRef = s.density;
  std::fill(lambda.begin(), lambda.end(), -7.0f);
  std::fill(lambdaSum.begin(), lambdaSum.end(), 0.0f);
  std::fill(s.density.begin(), s.density.end(), -7.0f);
  for (size_t i = 0; i < n; ++i) PbfLambdaListStage{lambdaStage}(static_cast<int>(i));
  auto grad = [&](double r) {
    const double q = r / k.H;
    return q <= 0.5 ? k.gradA * (3.0 * q - 2.0) : -k.gradB * (1.0 - q) * (1.0 - q) / r;
  };
  auto kernelW = [&](double r) {
    const double q = r / k.H;
    return q <= 0.5 ? k.sigma * (6.0 * (q * q * q - q * q) + 1.0) : k.sigma * 2.0 * (1.0 - q) * (1.0 - q) * (1.0 - q);
  };
  // f(j or -1 - b, d, r, Psi) over every other fluid particle and every wall particle within the support
  auto pairs = [&](size_t i, auto&& fn) {
    const Vec3 xi = Xyz(s.position[i]);
    for (size_t j = 0; j < n; ++j) {
      const double d[3] = {double(xi.x) - s.position[j].x, double(xi.y) - s.position[j].y, double(xi.z) - s.position[j].z};
      const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (j != i && r < k.H) fn(static_cast<long>(j), d, r, 0.0);
    }
    for (size_t b = 0; b < s.boundary.size(); ++b) {
      const double d[3] = {double(xi.x) - s.boundary[b].x, double(xi.y) - s.boundary[b].y, double(xi.z) - s.boundary[b].z};
      const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (r < k.H) fn(-1 - static_cast<long>(b), d, r, double(s.boundary[b].w));
    }
  };
  for (size_t i = 0; i < n; ++i) {
    double rho = ph.mass * kernelW(0.0), g[3] = {0, 0, 0}, sum2 = 0.0;
    int terms = 1;
    pairs(i, [&](long j, const double* d, double r, double psi) {
      ++terms;
      const double w = j >= 0 ? ph.mass * kernelW(r) : psi * kernelW(r);
      rho += w;
      const double c = j >= 0 ? ph.volume * grad(r) : psi * invRho0 * grad(r);
      for (int a = 0; a < 3; ++a) g[a] += d[a] * c;
      if (j >= 0) sum2 += c * c * r * r;
    });
    const double denom = sum2 + g[0] * g[0] + g[1] * g[1] + g[2] * g[2] + pbf.relaxation;
    const double lam = -std::max(rho * invRho0 - 1.0, 0.0) / denom;
    // float rounding: a sum of `terms` positive terms in any order is within terms * u of the exact one
    // (u = 2^-24; doubled for the kernel's own rounding), and lambda's numerator rho/rho0 - 1 carries that
    // rounding absolutely, its denominator relatively
    const double rel = 2.0 * terms * 5.96e-8;
    EXPECT_NEAR(s.density[i], rho, rel * rho) << "particle " << i;
    EXPECT_NEAR(s.density[i], densityRef[i], rel * rho) << "particle " << i;
    const double tol = rel * (rho * invRho0) / denom + 2.0 * rel * std::abs(lam);
    EXPECT_NEAR(lambda[i], lam, tol) << "particle " << i;
    EXPECT_NEAR(lambda[i], lambdaRef[i], tol) << "particle " << i;
  }
  // 2. the correction, from the same lambdas: the scalar stage, and the SIMD one from the pair cache and
  // own terms the SIMD lambda pass above left (with these lambdas: run it again on them)
  lambda = lambdaRef;
  const PbfCorrectStage correct{f.grid, f.fluid, f.list, ph, pbf, view};
  for (size_t i = 0; i < n; ++i) correct(static_cast<int>(i));
  deltaRef = delta;
  for (size_t i = 0; i < n; ++i) PbfLambdaListStage{lambdaStage}(static_cast<int>(i));  // lambda_i again (same values)
  std::fill(delta.begin(), delta.end(), Vec4{9.0f, 9.0f, 9.0f, 9.0f});
  for (size_t i = 0; i < n; ++i) PbfCorrectListStage{correct}(static_cast<int>(i));
  size_t moved = 0;
  for (size_t i = 0; i < n; ++i) {
    double dx[3] = {0, 0, 0}, scale = 0.0;
    const double li = lambda[i];
    pairs(i, [&](long j, const double* d, double r, double psi) {
      double c;
      if (j >= 0) {
        const double corr = -pbf.corrK * std::pow(kernelW(r) * pbf.invCorrW, pbf.corrN);
        c = (li + lambda[static_cast<size_t>(j)] + corr) * ph.volume * grad(r);
      } else {
        c = li * psi * invRho0 * grad(r);
      }
      for (int a = 0; a < 3; ++a) dx[a] += d[a] * c;
      scale += std::abs(c) * r;
    });
    const float got[3] = {delta[i].x, delta[i].y, delta[i].z}, ref[3] = {deltaRef[i].x, deltaRef[i].y, deltaRef[i].z};
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(got[a], dx[a], 1e-5 * scale + 1e-12) << "particle " << i << " axis " << a;
      EXPECT_NEAR(got[a], ref[a], 1e-5 * scale + 1e-12) << "particle " << i << " axis " << a;
      EXPECT_NEAR(ref[a], dx[a], 1e-5 * scale + 1e-12) << "scalar: particle " << i << " axis " << a;
    }
    if (li != 0.0) ++moved;
  }
  EXPECT_GT(moved, n / 20) << "the set must be compressed somewhere, or the correction is not tested";
  // 3. XSPH
  const PbfXsphStage xsph{f.grid, f.fluid, f.list, ph, pbf, view};
  for (size_t i = 0; i < n; ++i) xsph(static_cast<int>(i));
  deltaRef = delta;
  std::fill(delta.begin(), delta.end(), Vec4{9.0f, 9.0f, 9.0f, 9.0f});
  for (size_t i = 0; i < n; ++i) PbfXsphListStage{xsph}(static_cast<int>(i));
  for (size_t i = 0; i < n; ++i) {
    double dv[3] = {0, 0, 0}, scale = 0.0;
    pairs(i, [&](long j, const double*, double r, double) {
      if (j < 0) return;
      const Vec4 vj = s.velocity[static_cast<size_t>(j)], vi = s.velocity[i];
      const double w = pbf.xsph * ph.volume * kernelW(r);
      dv[0] += (double(vj.x) - vi.x) * w, dv[1] += (double(vj.y) - vi.y) * w, dv[2] += (double(vj.z) - vi.z) * w;
      scale += 2.0 * std::abs(w);  // |v| <= sqrt(3) m/s here
    });
    const float got[3] = {delta[i].x, delta[i].y, delta[i].z}, ref[3] = {deltaRef[i].x, deltaRef[i].y, deltaRef[i].z};
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(got[a], dv[a], 1e-5 * scale + 1e-12) << "particle " << i << " axis " << a;
      EXPECT_NEAR(got[a], ref[a], 1e-5 * scale + 1e-12) << "particle " << i << " axis " << a;
    }
  }
}

TEST(CpuStages, PbfPassesMatchPerParticleAndBruteForce) {
  ComparePbf(Random(3000, 0.0f, 0.16f, 6, 0.18f), 64, "random");
  const WallScene scene;
  ComparePbf(scene.water, 64, "walls", scene.walls);
  ComparePbf(Clustered(), 24, "clustered, lists overflowing");
}

/// DFSPH's three neighbour passes (solvers/dfsph/dfsph_simd.h) against the per-particle stages (solvers/dfsph/dfsph_stages.h)
/// and against their sums in double over every fluid and wall particle: the factor alpha_i with the
/// walls' gradient gB_i and the neighbour count, Predict's increment delta_i (the density solve's from
/// the compressed set's rho_i and D rho_i/Dt, the divergence solve's from D rho_i/Dt), and Correct's
/// velocity update. The SIMD passes read the lane-blocked cache the SIMD factor filled, the scalar ones
/// their Vec3 a slot.
void CompareDfsph(const std::vector<Vec3>& points, int maxNeighbours, const std::string& what,
                  const std::vector<Vec3>& walls = {}) {
  SCOPED_TRACE(what);
  Setup s(points, maxNeighbours, walls);
  Physics& ph = s.ph;
  ph.volume = kSpacing * kSpacing * kSpacing;
  s.RunBlocked(false, 0);  // the neighbour lists, the densities and the near-a-wall flags
  const size_t n = s.position.size();
  const ForceStage f = s.Forces();
  const CubicSpline k = ph.kernel;
  const double invRho0 = ph.invRestDensity;
  std::vector<float> kappa(n, 0.0f), kappaV(n, 0.0f), factor(n, -1.0f), delta(n, -1.0f);
  std::vector<Vec3> grad(n * static_cast<size_t>(maxNeighbours), Vec3{9.0f, 9.0f, 9.0f});
  std::vector<Vec4> boundary(n, Vec4{9.0f, 9.0f, 9.0f, 9.0f}), velocityStart(n);
  std::vector<int32_t> neighbours(n, -1);
  std::vector<uint64_t> error(n, 0);
  const int stride = PairCacheStride(maxNeighbours);
  std::vector<float> pairGrad(n * static_cast<size_t>(stride), std::numeric_limits<float>::quiet_NaN());
  DfsphView view{kappa.data(),      kappaV.data(), grad.data(),  boundary.data(),      factor.data(),
                 neighbours.data(), delta.data(),  error.data(), velocityStart.data(), pairGrad.data(),
                 stride};
  auto gradFactor = [&](double r) {
    const double q = r / k.H;
    return q <= 0.5 ? k.gradA * (3.0 * q - 2.0) : -k.gradB * (1.0 - q) * (1.0 - q) / r;
  };
  // f(j or -1 - b, G) over every other fluid particle (G = V grad W_ij) and every wall particle (G = Psi_b
  // / rho0 grad W_ib) within the support, in double
  // (`borderline`: how many of them lie within 1e-5 of the support's edge)
  auto pairs = [&](size_t i, auto&& fn, int* borderline = nullptr) {
    const Vec3 xi = Xyz(s.position[i]);
    auto visit = [&](long j, Vec4 p, double c) {
      const double d[3] = {double(xi.x) - p.x, double(xi.y) - p.y, double(xi.z) - p.z};
      const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (borderline && std::abs(r - k.H) < 1e-5 * k.H) ++*borderline;
      if (r >= (1.0 + 1e-5) * k.H || r == 0.0) return;
      const double g = c * gradFactor(r);
      const double G[3] = {d[0] * g, d[1] * g, d[2] * g};
      fn(j, G);
    };
    for (size_t j = 0; j < n; ++j) {
      if (j != i) visit(static_cast<long>(j), s.position[j], ph.volume);
    }
    for (size_t b = 0; b < s.boundary.size(); ++b) visit(-1 - static_cast<long>(b), s.boundary[b], s.boundary[b].w * invRho0);
  };
  constexpr double u = 5.96e-8;  // float's unit roundoff
  // 1. the factor: scalar, then SIMD (which fills the lane-blocked cache)
  const DfsphFactorStage factorStage{f.grid, f.fluid, f.list, ph, view};
  for (size_t i = 0; i < n; ++i) factorStage(static_cast<int>(i));
  const std::vector<float> factorRef = factor;
  const std::vector<Vec4> boundaryRef = boundary;
  const std::vector<int32_t> neighboursRef = neighbours;
  std::fill(factor.begin(), factor.end(), -1.0f);
  std::fill(boundary.begin(), boundary.end(), Vec4{9.0f, 9.0f, 9.0f, 9.0f});
  std::fill(neighbours.begin(), neighbours.end(), -1);
  for (size_t i = 0; i < n; ++i) DfsphFactorListStage{factorStage}(static_cast<int>(i));
  size_t nearWall = 0;
  for (size_t i = 0; i < n; ++i) {
    double sum[3] = {0, 0, 0}, gB[3] = {0, 0, 0}, sum2 = 0.0, scale = 0.0;
    int count = 0;
    pairs(i, [&](long j, const double* G) {
      ++count;
      for (int a = 0; a < 3; ++a) (j >= 0 ? sum : gB)[a] += G[a];
      if (j >= 0) sum2 += G[0] * G[0] + G[1] * G[1] + G[2] * G[2];
      scale += std::sqrt(G[0] * G[0] + G[1] * G[1] + G[2] * G[2]);
    });
    // The count: pairs within the support in float; a pair of the lattice two spacings apart sits on its
    // edge (rounding decides, and its G is ~0), so the count may hold any of those.
    int borderline = 0;
    pairs(i, [&](long, const double*) {}, &borderline);
    EXPECT_GE(neighbours[i], count - borderline) << "particle " << i;
    EXPECT_LE(neighbours[i], count) << "particle " << i;
    EXPECT_EQ(neighboursRef[i], neighbours[i]) << "particle " << i;
    const float got[3] = {boundary[i].x, boundary[i].y, boundary[i].z};
    const float ref[3] = {boundaryRef[i].x, boundaryRef[i].y, boundaryRef[i].z};
    // a sum of `count` terms in float, in any order: within 2 count u of their absolute sum
    const double sumTol = 2.0 * count * u * scale + 1e-12;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(got[a], gB[a], sumTol) << "particle " << i << " axis " << a;
      EXPECT_NEAR(ref[a], gB[a], sumTol) << "scalar: particle " << i << " axis " << a;
    }
    if (gB[0] != 0.0 || gB[1] != 0.0 || gB[2] != 0.0) ++nearWall;
    const double g[3] = {sum[0] + gB[0], sum[1] + gB[1], sum[2] + gB[2]};
    const double denominator = g[0] * (sum[0] + 2.0 * gB[0]) + g[1] * (sum[1] + 2.0 * gB[1]) +
                               g[2] * (sum[2] + 2.0 * gB[2]) + sum2;
    ASSERT_GT(denominator, 0.0);
    const double alpha = 1.0 / denominator;
    // The denominator's terms carry the sums' rounding (relative 2 count u of |G| sums, doubled in the
    // products) against a denominator of at least sum |G|^2: relative 8 count u (scale / |G|) is a bound
    // with room; alpha's relative error is the denominator's.
    const double rel = 8.0 * count * u * (1.0 + scale * scale / (sum2 > 0.0 ? sum2 * count : 1.0));
    EXPECT_NEAR(factor[i], alpha, rel * alpha) << "particle " << i;
    EXPECT_NEAR(factorRef[i], alpha, rel * alpha) << "scalar: particle " << i;
  }
  if (!walls.empty()) {
    EXPECT_GT(nearWall, n / 10) << "the wall case must put particles near the wall";
  }
  // 2. Predict, both solves: delta_i = residual alpha_i, from the same alpha_i (the SIMD factor's)
  const float dt = 1e-3f;
  for (bool densitySolve : {true, false}) {
    SCOPED_TRACE(densitySolve ? "density solve" : "divergence solve");
    const DfsphPredictStage predict{f.grid, f.fluid, f.list, ph, view, dt, densitySolve};
    for (size_t i = 0; i < n; ++i) predict(static_cast<int>(i));
    const std::vector<float> deltaRef = delta;
    std::fill(delta.begin(), delta.end(), -1.0f);
    for (size_t i = 0; i < n; ++i) DfsphPredictListStage{predict}(static_cast<int>(i));
    size_t pushed = 0;
    for (size_t i = 0; i < n; ++i) {
      const Vec4 vi = s.velocity[i];
      double rate = 0.0, scale = 0.0;
      int count = 0;
      pairs(i, [&](long j, const double* G) {
        ++count;
        const Vec4 vj = j >= 0 ? s.velocity[static_cast<size_t>(j)] : Vec4{0.0f, 0.0f, 0.0f, 0.0f};  // walls at rest
        const double term = (double(vi.x) - vj.x) * G[0] + (double(vi.y) - vj.y) * G[1] + (double(vi.z) - vj.z) * G[2];
        rate += term;
        scale += std::abs(double(vi.x) - vj.x) * std::abs(G[0]) + std::abs(double(vi.y) - vj.y) * std::abs(G[1]) +
                 std::abs(double(vi.z) - vj.z) * std::abs(G[2]);
      });
      double residual, residualTol;
      const double rateTol = 4.0 * (count + 3) * u * scale + 1e-12;
      if (densitySolve) {
        residual = std::max(s.density[i] * invRho0 + dt * rate - 1.0, 0.0);
        residualTol = 2.0 * u * (s.density[i] * invRho0) + dt * rateTol;
      } else {
        residual = neighbours[i] < kDfsphMinNeighbours ? 0.0 : std::max(rate, 0.0);
        residualTol = rateTol;
      }
      const double expected = residual * factor[i];
      const double tol = residualTol * factor[i] + 2.0 * u * expected;
      EXPECT_NEAR(delta[i], expected, tol) << "particle " << i;
      EXPECT_NEAR(deltaRef[i], expected, tol) << "scalar: particle " << i;
      if (expected > 0.0) ++pushed;
    }
    EXPECT_GT(pushed, n / 20) << "some particles must be pushed, or the increments are not tested";
  }
  // 3. Correct, from the divergence solve's increments above: dv_i = sum_j (delta_i + delta_j) G_ij +
  // 2 delta_i gB_i, v_i -= dv_i (c = 1)
  const std::vector<Vec4> v0 = s.velocity;
  const DfsphCorrectStage correct{f.grid, f.fluid, f.list, ph, view, 1.0f, false};
  for (size_t i = 0; i < n; ++i) correct(static_cast<int>(i));
  const std::vector<Vec4> vRef = s.velocity;
  s.velocity = v0;
  for (size_t i = 0; i < n; ++i) DfsphCorrectListStage{correct}(static_cast<int>(i));
  for (size_t i = 0; i < n; ++i) {
    double dv[3] = {0, 0, 0}, scale = 0.0;
    int count = 0;
    const double di = delta[i];
    pairs(i, [&](long j, const double* G) {
      ++count;
      const double c = j >= 0 ? di + delta[static_cast<size_t>(j)] : 2.0 * di;
      for (int a = 0; a < 3; ++a) dv[a] += c * G[a];
      scale += std::abs(c) * (std::abs(G[0]) + std::abs(G[1]) + std::abs(G[2]));
    });
    const double tol = 4.0 * (count + 2) * u * scale + 2.0 * u * 2.0;  // |v| < 2 m/s: its own rounding
    const float got[3] = {s.velocity[i].x, s.velocity[i].y, s.velocity[i].z}, ref[3] = {vRef[i].x, vRef[i].y, vRef[i].z};
    const float start[3] = {v0[i].x, v0[i].y, v0[i].z};
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(got[a], start[a] - dv[a], tol) << "particle " << i << " axis " << a;
      EXPECT_NEAR(ref[a], start[a] - dv[a], tol) << "scalar: particle " << i << " axis " << a;
    }
  }
}

TEST(CpuStages, DfsphPassesMatchPerParticleAndBruteForce) {
  CompareDfsph(Random(3000, 0.0f, 0.16f, 6, 0.18f), 64, "random");
  const WallScene scene;
  CompareDfsph(scene.water, 64, "walls", scene.walls);
  CompareDfsph(Clustered(), 24, "clustered, lists overflowing");
}

TEST(CpuStages, DensityRandomSetMatchesPerParticleAndBruteForce) {
  Compare(Random(3000, 0.0f, 0.16f, 1), 64, "random");
}

TEST(CpuStages, DensityClusteredSetWithOverFullCellsMatches) {
  // Three dense clusters: cells with far more than 16 particles (several blocks per cell).
  std::mt19937 rng(2);
  std::normal_distribution<float> nd(0.0f, 0.006f);
  std::vector<Vec3> p;
  const Vec3 centres[] = {{0.05f, 0.05f, 0.05f}, {0.1f, 0.08f, 0.11f}, {0.13f, 0.14f, 0.03f}};
  for (const Vec3& c : centres) {
    for (int i = 0; i < 600; ++i) {
      p.push_back(Vec3{std::clamp(c.x + nd(rng), 0.0f, 0.159f), std::clamp(c.y + nd(rng), 0.0f, 0.159f),
                       std::clamp(c.z + nd(rng), 0.0f, 0.159f)});
    }
  }
  Compare(p, 2000, "clustered");
  Compare(p, 24, "clustered, lists overflowing");
}

TEST(CpuStages, DensityCellBorderLatticeMatches) {
  // A lattice of pitch 0.4 cells: every fifth plane lies on a cell face, so many particles sit on
  // faces, edges and corners (no pair is exactly a support apart: 2.5 pitches is not a lattice distance).
  std::vector<Vec3> p;
  const float pitch = 0.4f * kSupport;
  for (int z = 0; z < 19; ++z)
    for (int y = 0; y < 19; ++y)
      for (int x = 0; x < 19; ++x) p.push_back(Vec3{x * pitch, y * pitch, z * pitch});
  Compare(p, 64, "cell-border lattice");
}

TEST(CpuStages, DensityOddRowEndAndOutsideTheGridMatch) {
  // x over the whole odd row (its last cell is a pair of one), and particles beyond the grid on every
  // side, which CellOf clamps into the edge cells.
  std::vector<Vec3> p = Random(3000, 0.0f, 0.16f, 4, 0.18f);
  std::vector<Vec3> outside = Random(200, -0.01f, 0.17f, 5, 0.19f);
  p.insert(p.end(), outside.begin(), outside.end());
  Compare(p, 64, "odd row, outside");
}

TEST(CpuStages, DensityReuseMasksLanesThatDoNotCompute) {
  Compare(Random(3000, 0.0f, 0.16f, 3), 64, "random, reuse", /*reuse=*/true);
}

/// A lattice with `perCell` particles in every cell of a box of cells, jittered inside its cell.
std::vector<Vec3> PerCell(int cellsX, int cellsY, int cellsZ, int perCell, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.02f, 0.98f);
  std::vector<Vec3> p;
  for (int z = 0; z < cellsZ; ++z)
    for (int y = 0; y < cellsY; ++y)
      for (int x = 0; x < cellsX; ++x)
        for (int k = 0; k < perCell; ++k) {
          p.push_back(Vec3{(x + u(rng)) * kSupport, (y + u(rng)) * kSupport, (z + u(rng)) * kSupport});
        }
  return p;
}

// Spray (far fewer particles than cells): the blocks span boxes of up to 4 x 4 x 4 cells.
TEST(CpuStages, DensitySprayInBoxBlocksMatches) {
  Compare(Random(400, 0.0f, 0.16f, 11), 64, "spray");
  Compare(Random(400, 0.0f, 0.16f, 12), 64, "spray, reuse", /*reuse=*/true);
  const WallScene scene;
  std::vector<Vec3> low = Random(300, 0.0f, 0.16f, 13, 0.18f);  // spray low over the floor
  for (Vec3& v : low) v.y *= 0.3f;
  Compare(low, 64, "spray over walls", /*reuse=*/false, scene.walls);
}

// Cells of 9 and 12 (pairs of 18 and 24): their blocks are cut per cell, not per pair.
TEST(CpuStages, DensityCrowdedPairsCutPerCellMatch) {
  Compare(PerCell(8, 8, 8, 9, 14), 64, "9 per cell");
  Compare(PerCell(7, 8, 8, 12, 15), 64, "12 per cell, odd row", /*reuse=*/true);
}

/// Puts each entry of `set` from its block's start up to kLanes or its box's end into `blockOf` (by
/// particle; -1: in no block), failing where a particle lands in two blocks or outside its box. Returns
/// each block's box.
std::vector<BlockBox> TileBlocks(const GridView& g, const BlockSet& set, const std::vector<uint32_t>& starts,
                                 const std::vector<Vec4>& position, std::vector<int>* blockOf) {
  blockOf->assign(position.size(), -1);
  std::vector<BlockBox> boxes;
  for (size_t b = 0; b < starts.size(); ++b) {
    const BlockBox box = BlockBoxOf(g, set, static_cast<int>(starts[b]), false);
    boxes.push_back(box);
    const uint32_t end = std::min<uint32_t>(box.end, starts[b] + kLanes);
    EXPECT_GT(end, starts[b]) << "block " << b << " is empty";
    for (uint32_t e = starts[b]; e < end; ++e) {
      const uint32_t i = set.Particle(e);
      EXPECT_EQ((*blockOf)[i], -1) << "particle " << i << " in two blocks";
      (*blockOf)[i] = static_cast<int>(b);
      int cx, cy, cz;
      g.CellOf(Xyz(position[i]), &cx, &cy, &cz);
      EXPECT_TRUE(cx >= box.x0 && cx <= box.x1 && cy >= box.y0 && cy <= box.y1 && cz >= box.z0 && cz <= box.z1)
          << "particle " << i << " outside its block's box";
    }
  }
  return boxes;
}

// The blocks tile the particles: each particle in exactly one block of at most kLanes, every block's
// particles inside its box; spray takes boxes of several cells, and crowded pairs are cut per cell.
TEST(CpuStages, DensityBlocksTileTheParticles) {
  struct Case {
    std::string what;
    std::vector<Vec3> points;
    int minLevel, maxLevel;  // levels that some block must reach
  };
  const std::vector<Case> cases = {
      {"spray", Random(400, 0.0f, 0.16f, 11), 4, kMaxBlockLevel},
      {"random", Random(3000, 0.0f, 0.16f, 1), 1, 2},
      // more than kLanes in a pair of cells, at most kLanes in one (9 with AVX-512's 16 lanes, 5 with AVX's 8)
      {"crowded pairs", PerCell(8, 8, 8, kLanes / 2 + 1, 14), 1, 1},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    struct Setup s(c.points, 64);
    const GridView g = s.Grid();
    const int n = static_cast<int>(s.position.size());
    const std::vector<uint32_t> keys = s.Keys();
    const std::vector<uint32_t> starts = s.BlockStarts(keys, false), pairStarts = s.BlockStarts(keys, true);
    std::vector<int> blockOf;
    int deepest = 0, shallowest = kMaxBlockLevel, singleCells = 0;
    for (const BlockBox& box : TileBlocks(g, BlockSet{keys.data(), n}, starts, s.position, &blockOf)) {
      deepest = std::max(deepest, box.level);
      shallowest = std::min(shallowest, box.level);
      if (box.level == 1 && box.x0 == box.x1) ++singleCells;
    }
    for (int i = 0; i < n; ++i) ASSERT_NE(blockOf[i], -1) << "particle " << i << " in no block";
    EXPECT_GE(deepest, c.minLevel);
    EXPECT_LE(shallowest, c.maxLevel);
    if (c.what == "spray") {
      EXPECT_LT(starts.size() * 2, pairStarts.size()) << "spray in boxes: far fewer blocks than pairs";
    }
    if (c.what == "crowded pairs") {  // every pair of cells is cut into its two cells: one block each
      EXPECT_EQ(singleCells, static_cast<int>(starts.size()));
      EXPECT_EQ(starts.size(), pairStarts.size());
    }
  }
}

// With reuse the blocks are drawn from the particles that compute only: each of them in exactly one
// block, inside its box, no particle that reuses in any; with half of crowded water reusing, the blocks
// take fewer lanes idle, so there are fewer of them than of the masked layout's.
TEST(CpuStages, DensityBlocksOfTheComputingParticlesTileThem) {
  constexpr int kIdle = 3;
  for (const int perCell : {kLanes / 2 + 1, kLanes}) {  // (9 and 16 with AVX-512's 16 lanes)
    SCOPED_TRACE(std::to_string(perCell) + " per cell");
    struct Setup s(PerCell(8, 8, 8, perCell, 21), 64);
    const int n = static_cast<int>(s.position.size());
    for (int i = 0; i < n; ++i) s.idle[i] = i % 2 == 0 ? 2 : -1;  // every other particle reuses
    const GridView g = s.Grid();
    const std::vector<uint32_t> keys = s.Keys();
    const BlockSet set = s.ComputingSet(keys, kIdle);
    ASSERT_GT(set.count, n / 3);
    ASSERT_LT(set.count, 2 * n / 3);
    const std::vector<uint32_t> starts = s.BlockStarts(set, false), masked = s.BlockStarts(keys, false);
    std::vector<int> blockOf;
    TileBlocks(g, set, starts, s.position, &blockOf);
    for (int i = 0; i < n; ++i) {
      if (s.idle[i] > 0) {
        EXPECT_EQ(blockOf[i], -1) << "particle " << i << " reuses, yet takes a lane";
      } else {
        ASSERT_NE(blockOf[i], -1) << "particle " << i << " computes, yet is in no block";
      }
    }
    EXPECT_LT(starts.size() * 3, masked.size() * 2) << "half the particles reuse: far fewer blocks than masked lanes";
  }
}


// Reuse's crowding N_i (ActivityStage): the particles, fluid and wall, of the 27 cells around each
// particle's cell, counted per cell by CellCountStage and summed over the 27 cells by CellBoxSumStage's three passes (both backends' stages), against counting
// every particle's cell by brute force; and the classification that reads it.
TEST(Activity, CrowdCountsTheParticlesOfThe27CellsAroundAndClassifiesByIt) {
  const WallScene scene;
  std::vector<Vec3> water = scene.water;
  // Sparse water above the pool and some beyond the grid's edges (CellOf clamps it into edge cells).
  for (const Vec3& p : Random(400, 0.0f, 0.16f, 9, 0.18f)) water.push_back(Vec3{p.x, 0.07f + 0.5f * p.y, p.z});
  for (const Vec3& p : Random(40, -0.01f, 0.17f, 10, 0.19f)) water.push_back(p);
  struct Setup s(water, 64, scene.walls);
  const GridView g = s.Grid();
  std::vector<uint32_t> count(s.start.size(), 0xdeadbeefu), crowd(s.start.size(), 0xdeadbeefu);
  const CellCountStage countStage{g, count.data()};
  for (int c = 0; c < static_cast<int>(count.size()); ++c) countStage(c);
  for (int axis = 0; axis < 3; ++axis) {  // the backend's three passes, the two buffers in turn
    const CellBoxSumStage pass{g, axis == 1 ? crowd.data() : count.data(), axis == 1 ? count.data() : crowd.data(), axis};
    for (int row = 0; row < g.ny * g.nz; ++row) pass(row);
  }

  auto cellOf = [&](Vec3 p) {
    int c[3];
    g.CellOf(p, &c[0], &c[1], &c[2]);
    return std::array<int, 3>{c[0], c[1], c[2]};
  };
  auto within = [](const std::array<int, 3>& a, const std::array<int, 3>& b) {
    return std::abs(a[0] - b[0]) <= 1 && std::abs(a[1] - b[1]) <= 1 && std::abs(a[2] - b[2]) <= 1;
  };
  FluidView f = s.Stage().fluid;
  s.ph.reuseDelta1 = 0.0f;  // crowding alone: ACT_i = N_CPN / N_i
  s.ph.reuseDelta2 = 1.0f;
  s.ph.reuseCellCount = 8.0f;
  s.ph.reuseThreshold = 1.3f;
  s.ph.reuseIdle = 3;
  s.ph.reuseInvPressureScale = 1.0f;
  s.ph.reuseSyncStep = true;  // the impulse hold classifies on its synchronised steps only
  const ActivityStage activity{g, f, s.ph, crowd.data()};
  size_t inactive = 0, active = 0;
  for (size_t i = 0; i < s.position.size(); ++i) {
    const std::array<int, 3> ci = cellOf(Xyz(s.position[i]));
    uint32_t expected = 0;
    for (const Vec4& q : s.position) expected += within(ci, cellOf(Xyz(q))) ? 1u : 0u;
    for (const Vec4& b : s.boundary) expected += within(ci, cellOf(Xyz(b))) ? 1u : 0u;
    ASSERT_EQ(crowd[g.Linear(ci[0], ci[1], ci[2])], expected) << "particle " << i;
    activity(static_cast<int>(i));
    // Inactive (IC = IDLE) where the mean count of the 27 cells exceeds N_CPN / T.
    const bool crowded = 8.0 / (static_cast<double>(expected) / 27.0) < 1.3;
    ASSERT_EQ(s.idle[i], crowded ? 3 : -1) << "particle " << i << ", " << expected << " around";
    ++(crowded ? inactive : active);
  }
  // Both outcomes occur: the pool is crowded, the sparse water and the strays are not.
  EXPECT_GT(inactive, 500u);
  EXPECT_GT(active, 100u);
}

}  // namespace
}  // namespace sphxr::sim

namespace sphxr::sim {
namespace {

// The step's maxima combine inline (MaxDroppingNaN), not through libm's fmaxf: the same value as
// fmaxf for every pair of the values below, NaN dropped from either side (a NaN particle must not hide
// the others' maxima; StepReductionOp counts it on its own), and NaN only when both are.
TEST(StepReduction, MaximaAreFmaxfsAndDropNaN) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<float> values = {0.0f, 1e-30f, 0.5f, 1.0f, 2.0f, 3.4e38f, inf, -1.0f, -inf, nan};
  for (float a : values) {
    for (float b : values) {
      const float got = MaxDroppingNaN(a, b), want = std::fmax(a, b);
      if (std::isnan(want)) {
        EXPECT_TRUE(std::isnan(got)) << a << ", " << b;
      } else {
        EXPECT_EQ(got, want) << a << ", " << b;
      }
    }
  }
  StepReduction x, y;
  x.maxSpeed2 = nan;
  x.maxAccel2 = 4.0f;
  x.maxDensityError = 0.25f;
  y.maxSpeed2 = 9.0f;
  y.maxAccel2 = nan;
  y.maxDensityError = 0.5f;
  for (const StepReduction& r : {StepReductionCombine{}(x, y), StepReductionCombine{}(y, x)}) {
    EXPECT_EQ(r.maxSpeed2, 9.0f);
    EXPECT_EQ(r.maxAccel2, 4.0f);
    EXPECT_EQ(r.maxDensityError, 0.5f);
  }
}

}  // namespace
}  // namespace sphxr::sim
