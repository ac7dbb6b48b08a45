// The water surface (histogram-pyramid marching cubes, sim/src/surface_*.h) against a plain serial
// marching cubes written for the test (reference_mc.h) on analytic fields, against analytic areas,
// volumes and topology, and on particles: a single particle's analytic iso-sphere, water at rest in a
// box against its true free-surface height.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <unordered_map>

#include "backend.h"
#include "kernel.h"
#include "reference_mc.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/surface.h"
#include "support.h"

namespace sphxr::test {
namespace {

using sim::SurfaceGrid;
using sim::SurfaceMesh;
using sim::SurfaceStats;

constexpr double kPi = 3.14159265358979323846;

/// A cubic lattice of n^3 samples over [lo, hi]^3.
SurfaceGrid CubeGrid(int n, float lo, float hi) {
  SurfaceGrid g;
  g.origin = Vec3{lo, lo, lo};
  g.cellSize = (hi - lo) / static_cast<float>(n - 1);
  g.nx = g.ny = g.nz = n;
  return g;
}

std::vector<float> Sample(const SurfaceGrid& g, const std::function<double(double, double, double)>& f) {
  std::vector<float> v(static_cast<size_t>(g.Samples()));
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const double x = g.origin.x + static_cast<double>(i) * g.cellSize;
        const double y = g.origin.y + static_cast<double>(j) * g.cellSize;
        const double z = g.origin.z + static_cast<double>(k) * g.cellSize;
        v[static_cast<size_t>(i) + static_cast<size_t>(g.nx) * (j + static_cast<size_t>(g.ny) * k)] =
            static_cast<float>(f(x, y, z));
      }
  return v;
}

/// HPMC on the CPU backend (one thread) over a given field.
SurfaceMesh Hpmc(const SurfaceGrid& grid, const std::vector<float>& field, float iso, SurfaceStats* statsOut = nullptr) {
  auto backend = sim::MakeCpuBackend(1);
  sim::SurfaceExtractor* s = backend->Surface();
  SurfaceStats stats;
  EXPECT_TRUE(s->BuildFromField(grid, field, iso, &stats).ok());
  sim::SurfaceMeshView view;
  EXPECT_TRUE(s->WriteOwned(&view, &stats).ok());
  EXPECT_EQ(view.vertexCount, stats.vertices);
  EXPECT_FALSE(view.onDevice);
  SurfaceMesh mesh;
  s->DownloadMesh(&mesh);
  if (statsOut) *statsOut = stats;
  return mesh;
}

Vec3 P(const std::vector<float>& p, size_t v) { return Vec3{p[3 * v], p[3 * v + 1], p[3 * v + 2]}; }

/// Welds vertices with bitwise-equal positions (the code interpolates every edge from its lower
/// corner, so a vertex shared by two cells is computed identically in both).
std::vector<int> WeldExact(const std::vector<float>& p, int* unique) {
  struct Hash {
    size_t operator()(const std::array<uint32_t, 3>& a) const {
      return (static_cast<size_t>(a[0]) * 73856093u) ^ (static_cast<size_t>(a[1]) * 19349663u) ^
             (static_cast<size_t>(a[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<uint32_t, 3>, int, Hash> ids;
  std::vector<int> out(p.size() / 3);
  for (size_t v = 0; v < out.size(); ++v) {
    std::array<uint32_t, 3> key;
    std::memcpy(key.data(), &p[3 * v], 12);
    auto [it, fresh] = ids.emplace(key, static_cast<int>(ids.size()));
    out[v] = it->second;
  }
  *unique = static_cast<int>(ids.size());
  return out;
}

struct Topology {
  int vertices = 0, edges = 0, faces = 0;
  int boundaryEdges = 0;     // in one triangle
  int nonManifoldEdges = 0;  // in three or more
  int misoriented = 0;       // a directed edge used twice (neighbours disagree on orientation)
  int degenerate = 0;        // a triangle with two welded vertices equal
  int Euler() const { return vertices - edges + faces; }
};

Topology Analyse(const SurfaceMesh& mesh, std::vector<std::pair<int, int>>* boundary = nullptr) {
  Topology t;
  const std::vector<int> id = WeldExact(mesh.positions, &t.vertices);
  std::map<std::pair<int, int>, int> undirected;
  std::map<std::pair<int, int>, int> directed;
  t.faces = static_cast<int>(id.size() / 3);
  for (size_t f = 0; f < id.size() / 3; ++f) {
    const int v[3] = {id[3 * f], id[3 * f + 1], id[3 * f + 2]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++t.degenerate;
    for (int e = 0; e < 3; ++e) {
      const int a = v[e], b = v[(e + 1) % 3];
      ++undirected[{std::min(a, b), std::max(a, b)}];
      ++directed[{a, b}];
    }
  }
  t.edges = static_cast<int>(undirected.size());
  for (const auto& [e, n] : undirected) {
    if (n == 1) {
      ++t.boundaryEdges;
      if (boundary) boundary->push_back(e);
    }
    if (n > 2) ++t.nonManifoldEdges;
  }
  for (const auto& [e, n] : directed) t.misoriented += n > 1 ? 1 : 0;
  return t;
}

double Area(const SurfaceMesh& m) {
  double a = 0.0;
  for (int64_t t = 0; t < m.TriangleCount(); ++t) {
    const Vec3 p0 = P(m.positions, 3 * t), p1 = P(m.positions, 3 * t + 1), p2 = P(m.positions, 3 * t + 2);
    a += 0.5 * static_cast<double>(Length(Cross(p1 - p0, p2 - p0)));
  }
  return a;
}

/// Enclosed volume by the divergence theorem (positive when the triangles face outwards).
double Volume(const SurfaceMesh& m) {
  double v = 0.0;
  for (int64_t t = 0; t < m.TriangleCount(); ++t) {
    const Vec3 p0 = P(m.positions, 3 * t), p1 = P(m.positions, 3 * t + 1), p2 = P(m.positions, 3 * t + 2);
    v += static_cast<double>(Dot(p0, Cross(p1, p2))) / 6.0;
  }
  return v;
}

/// HPMC and the reference have the same triangles: same count, and every HPMC triangle matches a
/// reference triangle vertex by vertex within `tol` (same orientation), as multisets.
void ExpectSameTriangles(const SurfaceMesh& hpmc, const ReferenceMesh& ref, float tol = 1e-5f) {
  ASSERT_EQ(hpmc.VertexCount(), ref.VertexCount());
  ASSERT_EQ(hpmc.VertexCount() % 3, 0);
  // Reference vertices into a hash grid of cell `tol`; a query looks at the 27 cells around it.
  using Key = std::array<int64_t, 3>;
  struct Hash {
    static uint64_t Mix(uint64_t x) {  // splitmix64's finaliser
      x ^= x >> 30;
      x *= 0xbf58476d1ce4e5b9ull;
      x ^= x >> 27;
      x *= 0x94d049bb133111ebull;
      return x ^ (x >> 31);
    }
    size_t operator()(const Key& k) const {
      return static_cast<size_t>(Mix(static_cast<uint64_t>(k[0]) + Mix(static_cast<uint64_t>(k[1]) + Mix(static_cast<uint64_t>(k[2])))));
    }
  };
  auto keyOf = [tol](Vec3 p) {
    return Key{static_cast<int64_t>(std::floor(p.x / tol)), static_cast<int64_t>(std::floor(p.y / tol)),
               static_cast<int64_t>(std::floor(p.z / tol))};
  };
  std::unordered_map<Key, std::vector<int>, Hash> cells;
  cells.reserve(static_cast<size_t>(ref.VertexCount()));
  std::vector<Vec3> unique;
  std::vector<int> refId(static_cast<size_t>(ref.VertexCount()));
  auto find = [&](Vec3 p) -> int {
    const Key k = keyOf(p);
    auto within = [&](int u) {
      const Vec3 d = unique[static_cast<size_t>(u)] - p;
      return std::fabs(d.x) <= tol && std::fabs(d.y) <= tol && std::fabs(d.z) <= tol;
    };
    if (auto it = cells.find(k); it != cells.end()) {  // the usual case: the same cell
      for (int u : it->second) {
        if (within(u)) return u;
      }
    }
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = cells.find(Key{k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == cells.end()) continue;
          for (int u : it->second) {
            if (within(u)) return u;
          }
        }
    return -1;
  };
  for (size_t v = 0; v < refId.size(); ++v) {
    const Vec3 p = P(ref.positions, v);
    int u = find(p);
    if (u < 0) {
      u = static_cast<int>(unique.size());
      unique.push_back(p);
      cells[keyOf(p)].push_back(u);
    }
    refId[v] = u;
  }
  auto canonical = [](int a, int b, int c) {  // rotate so the smallest id comes first (keeps orientation)
    if (b < a && b < c) return std::array<int, 3>{b, c, a};
    if (c < a && c < b) return std::array<int, 3>{c, a, b};
    return std::array<int, 3>{a, b, c};
  };
  std::vector<std::array<int, 3>> refTriangles, hpmcTriangles;
  for (size_t t = 0; t < refId.size() / 3; ++t) {
    refTriangles.push_back(canonical(refId[3 * t], refId[3 * t + 1], refId[3 * t + 2]));
  }
  // With reference normals: the normal of each matched vertex within 1e-4.
  std::vector<Vec3> refNormal(unique.size());
  if (!ref.normals.empty()) {
    for (size_t v = 0; v < refId.size(); ++v) refNormal[static_cast<size_t>(refId[v])] = P(ref.normals, v);
  }
  int unmatched = 0, normalsOff = 0;
  for (int64_t t = 0; t < hpmc.TriangleCount(); ++t) {
    int id[3];
    for (int c = 0; c < 3; ++c) {
      id[c] = find(P(hpmc.positions, static_cast<size_t>(3 * t + c)));
      if (id[c] < 0) ++unmatched;
      if (id[c] >= 0 && !ref.normals.empty()) {
        const Vec3 d = P(hpmc.normals, static_cast<size_t>(3 * t + c)) - refNormal[static_cast<size_t>(id[c])];
        normalsOff += Length(d) > 1e-4f ? 1 : 0;
      }
    }
    hpmcTriangles.push_back(canonical(id[0], id[1], id[2]));
  }
  ASSERT_EQ(unmatched, 0) << "HPMC vertices with no reference vertex within " << tol;
  EXPECT_EQ(normalsOff, 0) << "HPMC normals differing from the reference's by more than 1e-4";
  std::sort(refTriangles.begin(), refTriangles.end());
  std::sort(hpmcTriangles.begin(), hpmcTriangles.end());
  EXPECT_TRUE(refTriangles == hpmcTriangles) << "the triangle sets differ";
}

/// Every normal is unit length and on the outer side of its triangle's plane (the geometric normal of a
/// counter-clockwise triangle seen from outside agrees with -grad phi).
void ExpectOutwardUnitNormals(const SurfaceMesh& m, double minAgreeing = 0.99) {
  int64_t agreeing = 0, nonUnit = 0, counted = 0;
  for (int64_t t = 0; t < m.TriangleCount(); ++t) {
    const Vec3 p0 = P(m.positions, 3 * t), p1 = P(m.positions, 3 * t + 1), p2 = P(m.positions, 3 * t + 2);
    const Vec3 g = Cross(p1 - p0, p2 - p0);
    if (Length(g) == 0.0f) continue;
    Vec3 n{0, 0, 0};
    for (int c = 0; c < 3; ++c) {
      const Vec3 nc = P(m.normals, 3 * t + c);
      if (std::fabs(Length(nc) - 1.0f) > 1e-4f) ++nonUnit;
      n += nc;
    }
    ++counted;
    agreeing += Dot(n, g) > 0.0f ? 1 : 0;
  }
  EXPECT_EQ(nonUnit, 0);
  EXPECT_GE(static_cast<double>(agreeing), minAgreeing * static_cast<double>(counted));
}

// ---- the case table ----------------------------------------------------------------------------------

TEST(SurfaceTable, EveryCaseClosesAndComplementsMirror) {
  // Case 0 and 255 are empty; every other case has 1 to 5 triangles, and the complement of a case
  // crosses the same edges.
  for (int mask = 0; mask < 256; ++mask) {
    const int n = sim::kMcTables.vertexCount[mask];
    EXPECT_EQ(n % 3, 0);
    if (mask == 0 || mask == 255) EXPECT_EQ(n, 0);
    else EXPECT_GE(n, 3) << "case " << mask;
    uint32_t edges = 0, complementEdges = 0;
    for (int k = 0; k < n; ++k) edges |= 1u << sim::kMcTables.edges[mask][k];
    for (int k = 0; k < sim::kMcTables.vertexCount[255 - mask]; ++k) complementEdges |= 1u << sim::kMcTables.edges[255 - mask][k];
    EXPECT_EQ(edges, complementEdges) << "case " << mask;
    // Exactly the edges whose corners differ are crossed.
    uint32_t expected = 0;
    for (int e = 0; e < 12; ++e) {
      const bool a = (mask >> sim::McEdgeCorner(e, 0)) & 1, b = (mask >> sim::McEdgeCorner(e, 1)) & 1;
      if (a != b) expected |= 1u << e;
    }
    EXPECT_EQ(edges, expected) << "case " << mask;
  }
}

TEST(SurfaceTable, RandomFieldsGiveClosedOrientedSurfaces) {
  // Random values exercise all 256 cases and every pair of neighbouring cases across a face; a border
  // of zeros closes the surface. Each welded edge must lie in exactly two triangles, once each way.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const SurfaceGrid g = CubeGrid(18, 0.0f, 1.0f);
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<float> f(static_cast<size_t>(g.Samples()));
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) {
          const bool border = i == 0 || j == 0 || k == 0 || i == g.nx - 1 || j == g.ny - 1 || k == g.nz - 1;
          f[static_cast<size_t>(i + g.nx * (j + g.ny * k))] = border ? 0.0f : u(rng);
        }
    const SurfaceMesh m = Hpmc(g, f, 0.5f);
    ASSERT_GT(m.TriangleCount(), 1000);
    const Topology t = Analyse(m);
    EXPECT_EQ(t.boundaryEdges, 0);
    EXPECT_EQ(t.nonManifoldEdges, 0);
    EXPECT_EQ(t.misoriented, 0);
    EXPECT_EQ(t.degenerate, 0);
    ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.5f));
  }
}

TEST(SurfaceTable, RandomFieldsOnOddAndTinyLatticesMatchTheReference) {
  // The pyramid's edges: every lattice from 2 to 11 samples per axis (odd and even cell counts, a
  // single cell, levels of one node along an axis), random values up to the lattice's border.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const int sizes[] = {2, 3, 4, 5, 6, 7, 10, 11};
  int64_t triangles = 0;
  for (int nx : sizes)
    for (int ny : sizes)
      for (int nz : sizes) {
        SurfaceGrid g;
        g.origin = Vec3{-0.3f, 0.1f, 0.7f};
        g.cellSize = 0.05f;
        g.nx = nx;
        g.ny = ny;
        g.nz = nz;
        std::vector<float> f(static_cast<size_t>(g.Samples()));
        for (float& v : f) v = u(rng);
        const SurfaceMesh m = Hpmc(g, f, 0.5f);
        SCOPED_TRACE(::testing::Message() << nx << " x " << ny << " x " << nz);
        ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.5f));  // (random gradients: normals ill-conditioned)
        triangles += m.TriangleCount();
      }
  EXPECT_GT(triangles, 10000);
}

// ---- analytic fields -----------------------------------------------------------------------------------

TEST(Surface, SphereMatchesReferenceAndAnalyticAreaAndVolume) {
  // Signed distance of a sphere of radius 0.3 (inside positive) on 64^3 samples over [-0.5, 0.5]^3.
  const double r = 0.3;
  const SurfaceGrid g = CubeGrid(64, -0.5f, 0.5f);
  const auto f = Sample(g, [r](double x, double y, double z) { return r - std::sqrt(x * x + y * y + z * z); });
  SurfaceStats stats;
  const SurfaceMesh m = Hpmc(g, f, 0.0f, &stats);
  ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.0f, /*normals=*/true));
  const Topology t = Analyse(m);
  EXPECT_EQ(t.boundaryEdges, 0);
  EXPECT_EQ(t.nonManifoldEdges, 0);
  EXPECT_EQ(t.misoriented, 0);
  EXPECT_EQ(t.Euler(), 2) << "a sphere";
  const double area = Area(m), volume = Volume(m);
  const double trueArea = 4.0 * kPi * r * r, trueVolume = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(area / trueArea, 1.0, 0.01) << "area " << area << " vs " << trueArea;
  EXPECT_NEAR(volume / trueVolume, 1.0, 0.01) << "volume " << volume << " vs " << trueVolume;
  ExpectOutwardUnitNormals(m);
  // Normals from the field's gradient: radial within a few degrees.
  double worst = 1.0;
  for (int64_t v = 0; v < m.VertexCount(); ++v) {
    const Vec3 p = P(m.positions, static_cast<size_t>(v)), n = P(m.normals, static_cast<size_t>(v));
    worst = std::min(worst, static_cast<double>(Dot(n, p * (1.0f / Length(p)))));
  }
  EXPECT_GT(worst, std::cos(5.0 * kPi / 180.0));
  // Pyramid memory: every level above the base is 1/8 of the one below (rounded up).
  EXPECT_EQ(stats.baseBytes, 63 * 63 * 63 * 4);
  EXPECT_LE(stats.pyramidBytes, 1.2 * static_cast<double>(stats.baseBytes));
}

TEST(Surface, TorusMatchesReferenceAndIsClosedWithGenusOne) {
  const double big = 0.3, small = 0.1;
  const SurfaceGrid g = CubeGrid(64, -0.5f, 0.5f);
  const auto f = Sample(g, [&](double x, double y, double z) {
    const double q = std::sqrt(x * x + z * z) - big;
    return small - std::sqrt(q * q + y * y);
  });
  const SurfaceMesh m = Hpmc(g, f, 0.0f);
  ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.0f));
  const Topology t = Analyse(m);
  EXPECT_EQ(t.boundaryEdges, 0);
  EXPECT_EQ(t.nonManifoldEdges, 0);
  EXPECT_EQ(t.misoriented, 0);
  EXPECT_EQ(t.Euler(), 0) << "a torus";
  EXPECT_NEAR(Volume(m) / (2.0 * kPi * kPi * big * small * small), 1.0, 0.02);
  EXPECT_NEAR(Area(m) / (4.0 * kPi * kPi * big * small), 1.0, 0.02);
  ExpectOutwardUnitNormals(m);
}

TEST(Surface, TwoTouchingSpheresMatchReferenceAndAreWatertight) {
  // Two spheres of radius 0.2 touching at a point inside a cell (not on a sample), the field the
  // larger of their signed distances.
  const double r = 0.2;
  const SurfaceGrid g = CubeGrid(64, -0.5f, 0.5f);
  const double o = 0.5 * g.cellSize * 0.37;  // contact point off the lattice
  const auto f = Sample(g, [&](double x, double y, double z) {
    const double d1 = std::sqrt((x - o + r) * (x - o + r) + (y - o) * (y - o) + (z - o) * (z - o));
    const double d2 = std::sqrt((x - o - r) * (x - o - r) + (y - o) * (y - o) + (z - o) * (z - o));
    return std::max(r - d1, r - d2);
  });
  const SurfaceMesh m = Hpmc(g, f, 0.0f);
  ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.0f));
  const Topology t = Analyse(m);
  EXPECT_EQ(t.boundaryEdges, 0);
  EXPECT_EQ(t.nonManifoldEdges, 0);
  EXPECT_EQ(t.misoriented, 0);
  EXPECT_EQ(t.degenerate, 0);
  // Two spheres (Euler 4) or, if the lattice joins them at the contact, one surface of genus 0 (2).
  EXPECT_TRUE(t.Euler() == 4 || t.Euler() == 2) << "Euler characteristic " << t.Euler();
  EXPECT_NEAR(Volume(m) / (2.0 * 4.0 / 3.0 * kPi * r * r * r), 1.0, 0.02);
}

TEST(Surface, EmptyAndFullFieldsGiveNoTriangles) {
  const SurfaceGrid g = CubeGrid(20, 0.0f, 1.0f);
  SurfaceStats stats;
  EXPECT_EQ(Hpmc(g, std::vector<float>(static_cast<size_t>(g.Samples()), 0.0f), 0.5f, &stats).VertexCount(), 0);
  EXPECT_EQ(stats.vertices, 0);
  EXPECT_EQ(Hpmc(g, std::vector<float>(static_cast<size_t>(g.Samples()), 1.0f), 0.5f).VertexCount(), 0);
  // A lattice of one sample layer has no cells at all.
  SurfaceGrid flat = g;
  flat.nz = 1;
  EXPECT_EQ(Hpmc(flat, std::vector<float>(static_cast<size_t>(flat.Samples()), 1.0f), 0.5f).VertexCount(), 0);
}

TEST(Surface, FieldTouchingTheBorderGivesAnOpenSurfaceEndingOnTheBorder) {
  // A sphere centred on the lattice's corner: an eighth of it, open where the field is inside at the border.
  const double r = 0.6;
  SurfaceGrid g = CubeGrid(33, 0.0f, 1.0f);
  g.ny = 29;  // not a cube, not a power of two: the pyramid's rounding at the edges
  const auto f = Sample(g, [r](double x, double y, double z) { return r - std::sqrt(x * x + y * y + z * z); });
  const SurfaceMesh m = Hpmc(g, f, 0.0f);
  ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.0f, /*normals=*/true));
  std::vector<std::pair<int, int>> boundary;
  const Topology t = Analyse(m, &boundary);
  EXPECT_EQ(t.nonManifoldEdges, 0);
  EXPECT_EQ(t.misoriented, 0);
  EXPECT_GT(t.boundaryEdges, 0);
  // Every open edge lies on one of the three border planes through the sphere's centre.
  int unique = 0;
  const std::vector<int> id = WeldExact(m.positions, &unique);
  std::vector<Vec3> pos(static_cast<size_t>(unique));
  for (size_t v = 0; v < id.size(); ++v) pos[static_cast<size_t>(id[v])] = P(m.positions, v);
  int offBorder = 0;
  for (const auto& [a, b] : boundary) {
    const Vec3 pa = pos[static_cast<size_t>(a)], pb = pos[static_cast<size_t>(b)];
    const bool onPlane = (pa.x == 0.0f && pb.x == 0.0f) || (pa.y == 0.0f && pb.y == 0.0f) || (pa.z == 0.0f && pb.z == 0.0f);
    offBorder += onPlane ? 0 : 1;
  }
  EXPECT_EQ(offBorder, 0);
  EXPECT_NEAR(Area(m) / (0.5 * kPi * r * r), 1.0, 0.01) << "an eighth of the sphere's area";
}

TEST(Surface, AMillionTrianglesGrowTheBufferAndMatchTheReference) {
  // A gyroid: many sheets through the whole lattice.
  const SurfaceGrid g = CubeGrid(128, 0.0f, 1.0f);
  const double k = 2.0 * kPi / (11.0 * g.cellSize);
  const auto f = Sample(g, [k](double x, double y, double z) {
    return std::sin(k * x) * std::cos(k * y) + std::sin(k * y) * std::cos(k * z) + std::sin(k * z) * std::cos(k * x);
  });
  LogCapture log;
  SurfaceStats stats;
  const SurfaceMesh m = Hpmc(g, f, 0.1f, &stats);
  EXPECT_GE(m.TriangleCount(), 1000000);
  EXPECT_TRUE(stats.grew);
  EXPECT_GE(stats.capacity, stats.vertices);
  EXPECT_EQ(log.Count("mesh buffer grown"), 1) << log.All();
  ExpectSameTriangles(m, ReferenceMarchingCubes(g, f, 0.1f));
}

TEST(Surface, BufferGrowsOnlyWhenTheMeshDoesNotFitAndWriteToClampsASmallTarget) {
  auto backend = sim::MakeCpuBackend(1);
  sim::SurfaceExtractor* s = backend->Surface();
  const SurfaceGrid g = CubeGrid(40, -0.5f, 0.5f);
  auto sphere = [&](double r) {
    return Sample(g, [r](double x, double y, double z) { return r - std::sqrt(x * x + y * y + z * z); });
  };
  SurfaceStats stats;
  sim::SurfaceMeshView view;
  ASSERT_TRUE(s->BuildFromField(g, sphere(0.2), 0.0f, &stats).ok());
  ASSERT_TRUE(s->WriteOwned(&view, &stats).ok());
  EXPECT_TRUE(stats.grew);
  const int64_t capacity = stats.capacity;
  // A smaller mesh fits: no growth.
  stats = SurfaceStats{};
  ASSERT_TRUE(s->BuildFromField(g, sphere(0.1), 0.0f, &stats).ok());
  ASSERT_TRUE(s->WriteOwned(&view, &stats).ok());
  EXPECT_FALSE(stats.grew);
  EXPECT_EQ(stats.capacity, capacity);
  // A larger one grows it, never truncates.
  stats = SurfaceStats{};
  ASSERT_TRUE(s->BuildFromField(g, sphere(0.45), 0.0f, &stats).ok());
  ASSERT_TRUE(s->WriteOwned(&view, &stats).ok());
  EXPECT_TRUE(stats.grew);
  EXPECT_FALSE(stats.clamped);
  EXPECT_GE(stats.capacity, stats.vertices);
  EXPECT_EQ(view.vertexCount, stats.vertices);
  SurfaceMesh own;
  s->DownloadMesh(&own);
  const int64_t n = stats.vertices;
  // Caller memory too small by one vertex: the whole triangles that fit are written, nothing past the
  // capacity, and the report says so (the indirect draw command counts what was written).
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> pos(static_cast<size_t>(3 * n), nan), nor(pos.size(), nan);
  uint32_t draw[4] = {7, 7, 7, 7};
  ASSERT_TRUE(s->WriteTo(sim::SurfaceTarget{pos.data(), nor.data(), n - 1, draw}, &stats).ok());
  const sim::SurfaceWriteReport r = s->LastWrite();
  EXPECT_EQ(r.vertices, n);
  EXPECT_EQ(r.written, n - 3);
  EXPECT_EQ(r.capacity, n - 1);
  EXPECT_TRUE(r.Clamped());
  EXPECT_TRUE(stats.clamped);
  EXPECT_EQ(stats.vertices, n);
  EXPECT_EQ(draw[0], static_cast<uint32_t>(n - 3));
  EXPECT_EQ(draw[1], 1u);
  EXPECT_EQ(draw[2], 0u);
  EXPECT_EQ(draw[3], 0u);
  EXPECT_TRUE(std::equal(pos.begin(), pos.end() - 9, own.positions.begin()));
  EXPECT_TRUE(std::equal(nor.begin(), nor.end() - 9, own.normals.begin()));
  for (size_t i = pos.size() - 9; i < pos.size(); ++i) EXPECT_TRUE(std::isnan(pos[i]) && std::isnan(nor[i])) << i;
  // Big enough: the same mesh, not clamped.
  ASSERT_TRUE(s->WriteTo(sim::SurfaceTarget{pos.data(), nor.data(), n, draw}, &stats).ok());
  EXPECT_FALSE(s->LastWrite().Clamped());
  EXPECT_GT(s->LastWrite().write, r.write);
  EXPECT_EQ(draw[0], static_cast<uint32_t>(n));
  EXPECT_EQ(own.positions, pos);
  EXPECT_EQ(own.normals, nor);
  // No target at all: nothing written, the size still reported.
  ASSERT_TRUE(s->WriteTo(sim::SurfaceTarget{}, &stats).ok());
  EXPECT_EQ(s->LastWrite().vertices, n);
  EXPECT_EQ(s->LastWrite().written, 0);
}

TEST(Surface, RunsOfVerticesGiveBitwiseTheMeshOfOneDescentPerVertex) {
  // The traversal steps from a run's first vertex to the next ones (the next slot of the cell, the next
  // cell with vertices in the pyramid's order); every vertex must get the cell, slot and arithmetic of
  // its own descent (run 1). Fields: isolated inside samples (8 cells of one triangle each around each,
  // far apart: the step climbs many levels over empty bricks), a random field (every cell busy: steps
  // within cells and bricks), and a sphere cut by the lattice's border on a lattice of odd, uneven sizes
  // (padding at the pyramid's edges). Runs: short and odd ones, and ones that end at or past the
  // mesh's last vertex. Caller memory pre-filled with NaN, and a guard after it: a vertex a run skips
  // stays NaN, a run writing past the mesh changes the guard.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  struct Case {
    const char* name;
    SurfaceGrid grid;
    std::vector<float> field;
    float iso;
  };
  std::vector<Case> cases;
  {
    SurfaceGrid g = CubeGrid(45, 0.0f, 1.0f);
    g.ny = 38;
    g.nz = 27;
    std::vector<float> f(static_cast<size_t>(g.Samples()), 0.0f);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(f.size()) - 1);
    for (int n = 0; n < 40; ++n) f[static_cast<size_t>(pick(rng))] = 1.0f;
    cases.push_back({"isolated samples", g, f, 0.5f});
  }
  {
    SurfaceGrid g = CubeGrid(13, 0.0f, 1.0f);
    g.ny = 9;
    g.nz = 11;
    std::vector<float> f(static_cast<size_t>(g.Samples()));
    for (float& v : f) v = u(rng);
    cases.push_back({"random field", g, f, 0.5f});
  }
  {
    SurfaceGrid g = CubeGrid(35, 0.0f, 1.0f);
    g.ny = 29;
    g.nz = 19;
    const auto f = Sample(g, [](double x, double y, double z) {
      return 0.45 - std::sqrt((x - 0.3) * (x - 0.3) + (y - 0.2) * (y - 0.2) + (z - 0.1) * (z - 0.1));
    });
    cases.push_back({"sphere on the border", g, f, 0.0f});
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  constexpr int kGuard = 3 * 64;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    auto backend = sim::MakeCpuBackend(2);
    sim::SurfaceExtractor* s = backend->Surface();
    SurfaceStats stats;
    ASSERT_TRUE(s->BuildFromField(c.grid, c.field, c.iso, &stats).ok());
    sim::SurfaceMeshView view;
    ASSERT_TRUE(s->WriteOwned(&view, &stats).ok());  // the size, read back once
    const int64_t n = view.vertexCount;
    ASSERT_GT(n, 30);
    auto write = [&](int run, std::vector<float>* pos, std::vector<float>* nor) {
      pos->assign(static_cast<size_t>(3 * n + kGuard), nan);
      nor->assign(pos->size(), nan);
      s->SetTraversalRun(run);
      EXPECT_TRUE(s->WriteTo(sim::SurfaceTarget{pos->data(), nor->data(), n}, &stats).ok());
    };
    std::vector<float> pos1, nor1;
    write(1, &pos1, &nor1);
    ExpectSameTriangles(SurfaceMesh{{pos1.begin(), pos1.end() - kGuard}, {nor1.begin(), nor1.end() - kGuard}},
                        ReferenceMarchingCubes(c.grid, c.field, c.iso));
    const int big = static_cast<int>(n);
    for (int run : {2, 3, 5, 8, 13, 64, 255, 256, big - 1, big, big + 7}) {
      SCOPED_TRACE(::testing::Message() << "run " << run << " of " << n << " vertices");
      std::vector<float> pos, nor;
      write(run, &pos, &nor);
      int64_t firstDiff = -1;
      for (int64_t v = 0; v < n && firstDiff < 0; ++v) {
        if (std::memcmp(&pos[3 * v], &pos1[3 * v], 12) != 0 || std::memcmp(&nor[3 * v], &nor1[3 * v], 12) != 0) {
          firstDiff = v;
        }
      }
      EXPECT_EQ(firstDiff, -1) << "the first vertex that differs from its own descent's";
      int guardWritten = 0;
      for (size_t i = static_cast<size_t>(3 * n); i < pos.size(); ++i) guardWritten += std::isnan(pos[i]) && std::isnan(nor[i]) ? 0 : 1;
      EXPECT_EQ(guardWritten, 0);
    }
  }
}

// ---- from particles --------------------------------------------------------------------------------------

/// The radius where one particle's volume fraction dx^3 W(r) equals iso (support 2 dx), by bisection.
double SingleParticleRadius(double dx, double iso) {
  const sim::CubicSpline w = sim::CubicSpline::Make(static_cast<float>(2.0 * dx));
  double lo = 0.0, hi = 2.0 * dx;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (dx * dx * dx * w.W(static_cast<float>(mid)) > iso ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(SurfaceParticles, SingleParticleIsASphereOfTheKernelsIsoRadius) {
  const float dx = 0.05f;
  SceneSetup scene = TankScene({0, 0, 0}, {1, 1, 1}, dx);
  scene.fluid.push_back(Block({0.5f, 0.5f, 0.5f}, {0.55f, 0.55f, 0.55f}));
  auto solver = CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->FluidCount(), 1);
  const Vec3 c = Xyz(DownloadFluid(*solver).position[0]);
  // At the default iso level 0.5 a lone particle is below the surface everywhere (its peak volume
  // fraction is dx^3 W(0) = 1/pi): isolated spray draws no surface.
  SurfaceMesh mesh;
  SurfaceStats stats;
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh, &stats).ok());
  EXPECT_EQ(mesh.VertexCount(), 0);
  EXPECT_GT(stats.grid.Samples(), 0);
  // At iso 0.1 it is a closed sphere of the radius where dx^3 W(r) = 0.1.
  sim::SurfaceParams p;
  p.isoLevel = 0.1f;
  p.cellSize = dx / 4;
  ASSERT_TRUE(solver->ExtractSurface(p, &mesh, &stats).ok());
  ASSERT_GT(mesh.TriangleCount(), 50);
  const double rStar = SingleParticleRadius(dx, 0.1);
  double worst = 0.0;
  for (int64_t v = 0; v < mesh.VertexCount(); ++v) {
    const Vec3 d = P(mesh.positions, static_cast<size_t>(v)) - c;
    worst = std::max(worst, std::fabs(static_cast<double>(Length(d)) - rStar));
    EXPECT_GT(Dot(P(mesh.normals, static_cast<size_t>(v)), d), 0.0f) << "normal points into the particle";
  }
  // Linear interpolation of a field that is not linear along the edges: within a tenth of a cell.
  EXPECT_LT(worst, 0.1 * p.cellSize) << "r* = " << rStar;
  const Topology t = Analyse(mesh);
  EXPECT_EQ(t.boundaryEdges, 0);
  EXPECT_EQ(t.misoriented, 0);
  EXPECT_EQ(t.Euler(), 2);
}

TEST(SurfaceParticles, EmptySceneGivesNoTriangles) {
  auto solver = CreateOrFail(TankScene({0, 0, 0}, {0.2f, 0.2f, 0.2f}, 0.02f));
  ASSERT_TRUE(solver);
  ASSERT_EQ(solver->FluidCount(), 0);
  SurfaceMesh mesh;
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh).ok());
  EXPECT_EQ(mesh.VertexCount(), 0);
}

// The lattice is the clamp box's, so no particle position sizes it: non-finite particles add nothing to
// the field (a few among finite ones, or all of them).
TEST(SurfaceParticles, NonFiniteParticlesAddNothingToTheField) {
  auto solver = CreateOrFail(SmallDamBreak());
  ASSERT_TRUE(solver);
  HostFluid f = DownloadFluid(*solver);
  f.position[0].y = std::nanf("");
  ASSERT_TRUE(solver->Upload(f).ok());
  SurfaceMesh mesh;
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh).ok()) << "one NaN particle among finite ones";
  EXPECT_GT(mesh.TriangleCount(), 0);
  for (Vec4& p : f.position) p.x = std::nanf("");
  ASSERT_TRUE(solver->Upload(f).ok());
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh).ok());
  EXPECT_EQ(mesh.VertexCount(), 0);
}

TEST(SurfaceParticles, BadParametersAreRefusedWithTheKey) {
  auto solver = CreateOrFail(SmallDamBreak());
  ASSERT_TRUE(solver);
  SurfaceMesh mesh;
  sim::SurfaceParams p;
  p.cellSize = -1.0f;
  Status s = solver->ExtractSurface(p, &mesh);
  EXPECT_NE(s.message().find("surface.cell_size"), std::string::npos) << s.message();
  p = {};
  p.isoLevel = std::nanf("");
  s = solver->ExtractSurface(p, &mesh);
  EXPECT_NE(s.message().find("surface.iso_level"), std::string::npos) << s.message();
  p = {};
  p.cellSize = 1e-5f;  // 30,000 x 20,000 x 6,000 samples
  s = solver->ExtractSurface(p, &mesh);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("surface.cell_size"), std::string::npos) << s.message();
}

/// Top-surface vertices of a block of water that fills a tank's floor: |y - height| over the vertices
/// whose normal points up, away from the walls by more than the kernel support.
double TopSurfaceError(const SurfaceMesh& mesh, const SceneSetup& scene, double height, int* counted) {
  const float away = 2.5f * scene.params.spacing;
  double worst = 0.0;
  *counted = 0;
  for (int64_t v = 0; v < mesh.VertexCount(); ++v) {
    const Vec3 p = P(mesh.positions, static_cast<size_t>(v)), n = P(mesh.normals, static_cast<size_t>(v));
    if (n.y < 0.9f || p.y < 0.5f * static_cast<float>(height)) continue;
    if (p.x < scene.tank.min.x + away || p.x > scene.tank.max.x - away) continue;
    if (p.z < scene.tank.min.z + away || p.z > scene.tank.max.z - away) continue;
    worst = std::max(worst, std::fabs(static_cast<double>(p.y) - height));
    ++*counted;
  }
  return worst;
}

TEST(SurfaceParticles, WaterAtRestInABoxHasItsSurfaceAtTheFreeSurfaceHeight) {
  // 20 x 20 x 10 particles filling the floor of a 0.2 x 0.3 x 0.1 m tank to 0.2 m.
  const float dx = 0.01f;
  SceneSetup scene = TankScene({0, 0, 0}, {0.2f, 0.3f, 0.1f}, dx);
  scene.params.stiffness = 57000.0f;
  scene.params.viscosity = 0.3f;
  scene.params.boundaryViscosity = 0.3f;
  scene.params.maxDt = 1e-3f;
  scene.openTop = false;
  scene.fluid.push_back(Block({0, 0, 0}, {0.2f, 0.2f, 0.1f}));
  auto solver = CreateOrFail(scene);
  ASSERT_TRUE(solver);
  for (float cell : {dx, 0.5f * dx}) {
    sim::SurfaceParams p;
    p.cellSize = cell;
    // The rest lattice: the true surface is the block's top, half a spacing above the top particles.
    SurfaceMesh mesh;
    ASSERT_TRUE(solver->ExtractSurface(p, &mesh).ok());
    int counted = 0;
    EXPECT_LT(TopSurfaceError(mesh, scene, 0.2, &counted), 0.5 * dx) << "cell " << cell;
    EXPECT_GT(counted, 100);
  }
  // Settled for 0.3 s: the water is compressed by its weight; the true height is its volume over the
  // tank's floor, with the volume from the particles' mean density.
  ASSERT_TRUE(StepN(*solver, 300));
  const HostFluid host = DownloadFluid(*solver);
  double meanDensity = 0.0;
  for (float rho : host.density) meanDensity += rho;
  meanDensity /= static_cast<double>(host.size());
  const double height = static_cast<double>(host.size()) * solver->ParticleMass() / meanDensity / (0.2 * 0.1);
  SurfaceMesh mesh;
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh).ok());
  int counted = 0;
  EXPECT_LT(TopSurfaceError(mesh, scene, height, &counted), 0.5 * dx) << "true height " << height;
  EXPECT_GT(counted, 100);
  const Topology t = Analyse(mesh);
  EXPECT_EQ(t.boundaryEdges, 0) << "the margin keeps the surface closed";
  EXPECT_EQ(t.misoriented, 0);
}

/// The field at every sample against the kernel sum over all particles (brute force, doubles): the
/// largest absolute difference and the largest value. Fails the test if a sample was not written.
void CompareFieldWithBruteForce(const SurfaceGrid& g, const std::vector<float>& field, const std::vector<Vec4>& positions,
                                const sim::CubicSpline& w, float volume, double* worst, double* peak) {
  *worst = 0.0;
  *peak = 0.0;
  // Farther than the support from the particles' bounding box the field is exactly 0 (no sum needed).
  Vec3 lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  for (const Vec4& q : positions) {
    lo = Vec3{std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
    hi = Vec3{std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
  }
  const float reach = 1.001f * w.H;
  for (int kz = 0; kz < g.nz; ++kz)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const Vec3 x{g.origin.x + i * g.cellSize, g.origin.y + j * g.cellSize, g.origin.z + kz * g.cellSize};
        if (x.x < lo.x - reach || x.x > hi.x + reach || x.y < lo.y - reach || x.y > hi.y + reach ||
            x.z < lo.z - reach || x.z > hi.z + reach) {
          const float got = field[static_cast<size_t>(i + g.nx * (j + g.ny * kz))];
          ASSERT_EQ(got, 0.0f) << "sample " << i << ", " << j << ", " << kz << " beyond every particle's support";
          continue;
        }
        double sum = 0.0;
        for (const Vec4& q : positions) {
          const Vec3 d = x - Xyz(q);
          if (Dot(d, d) < w.H2) sum += volume * w.W(Length(d));
        }
        const float got = field[static_cast<size_t>(i + g.nx * (j + g.ny * kz))];
        ASSERT_TRUE(std::isfinite(got)) << "sample " << i << ", " << j << ", " << kz << " not written";
        *worst = std::max(*worst, std::fabs(sum - got));
        *peak = std::max(*peak, sum);
      }
}

TEST(SurfaceParticles, FieldMatchesABruteForceSumAndExtractionDoesNotChangeTheSimulation) {
  SceneSetup scene = SmallDamBreak();
  auto a = CreateOrFail(scene);
  auto b = CreateOrFail(scene);
  ASSERT_TRUE(a && b);
  for (int k = 0; k < 6; ++k) {
    ASSERT_TRUE(StepN(*a, 10));
    ASSERT_TRUE(StepN(*b, 10));
    SurfaceMesh mesh;
    SurfaceStats stats;
    ASSERT_TRUE(b->ExtractSurface(sim::SurfaceParams{}, &mesh, &stats).ok());
    EXPECT_GT(mesh.TriangleCount(), 100);
  }
  // Bit-identical particles: the extraction's re-sort is what the next step's stable sort does anyway.
  const HostFluid fa = DownloadFluid(*a), fb = DownloadFluid(*b);
  ASSERT_EQ(fa.size(), fb.size());
  const auto ib = IndexById(fb);
  int differ = 0;
  for (size_t i = 0; i < fa.size(); ++i) {
    const Vec4 pa = fa.position[i], pb = fb.position[ib.at(fa.id[i])];
    differ += (pa.x != pb.x || pa.y != pb.y || pa.z != pb.z) ? 1 : 0;
  }
  EXPECT_EQ(differ, 0);
  // The field at every sample against the sum over all particles.
  SurfaceStats stats;
  ASSERT_TRUE(b->BuildSurface(sim::SurfaceParams{}, &stats).ok());
  SurfaceGrid g;
  std::vector<float> field;
  b->BackendForTests()->Surface()->DownloadField(&g, &field);
  ASSERT_EQ(static_cast<int64_t>(field.size()), g.Samples());
  const sim::CubicSpline w = sim::CubicSpline::Make(b->SupportRadius());
  const float dx = scene.params.spacing, volume = dx * dx * dx;
  double worst = 0.0, peak = 0.0;
  CompareFieldWithBruteForce(g, field, fb.position, w, volume, &worst, &peak);
  if (HasFatalFailure()) return;
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(peak, 0.9);
  // The lattice covers the box the domain clamp keeps the particles in (a quarter spacing inside the
  // tank) plus the margin (the support radius), no more; on the CPU backend, whose particles are host
  // memory, only the particles' bounding box within it (kSurfaceOverParticles).
  const float inset = 0.25f * dx;
  Vec3 lo = scene.tank.min + Vec3{inset, inset, inset}, hi = scene.tank.max - Vec3{inset, inset, inset};
  if (b->ActiveDevice() == sim::Device::kCpu) {
    Vec3 pmin{1e9f, 1e9f, 1e9f}, pmax{-1e9f, -1e9f, -1e9f};
    for (const Vec4& q : fb.position) {
      pmin = Vec3{std::min(pmin.x, q.x), std::min(pmin.y, q.y), std::min(pmin.z, q.z)};
      pmax = Vec3{std::max(pmax.x, q.x), std::max(pmax.y, q.y), std::max(pmax.z, q.z)};
    }
    lo = Vec3{std::max(lo.x, pmin.x), std::max(lo.y, pmin.y), std::max(lo.z, pmin.z)};
    hi = Vec3{std::min(hi.x, pmax.x), std::min(hi.y, pmax.y), std::min(hi.z, pmax.z)};
  }
  const float m = b->SupportRadius();
  EXPECT_LE(g.origin.x, lo.x - m);
  EXPECT_GT(g.origin.x, lo.x - m - g.cellSize);
  EXPECT_GE(g.origin.y + (g.ny - 1) * g.cellSize, hi.y + m);
  EXPECT_LT(g.origin.y + (g.ny - 2) * g.cellSize, hi.y + m);
  EXPECT_LE(g.origin.z, lo.z - m);
  EXPECT_GE(g.origin.x + (g.nx - 1) * g.cellSize, hi.x + m);
}

TEST(SurfaceParticles, FieldMatchesABruteForceSumAtEveryCellSize) {
  // The field stage's blocks: 3 x 3 x 3 neighbour cells per block at 1.6 and 1 spacing, one at 0.5, and
  // sample by sample below (blocks of more than 8 samples per axis); a moving, splashing state.
  SceneSetup scene = SmallDamBreak();
  auto solver = CreateOrFail(scene);
  ASSERT_TRUE(solver);
  ASSERT_TRUE(StepN(*solver, 120));
  const HostFluid fluid = DownloadFluid(*solver);
  const sim::CubicSpline w = sim::CubicSpline::Make(solver->SupportRadius());
  const float dx = scene.params.spacing, volume = dx * dx * dx;
  for (float factor : {1.6f, 1.0f, 0.5f, 0.3f, 0.2f}) {
    SCOPED_TRACE(::testing::Message() << "cell size " << factor << " spacing");
    sim::SurfaceParams params;
    params.cellSize = factor * dx;
    SurfaceStats stats;
    ASSERT_TRUE(solver->BuildSurface(params, &stats).ok());
    SurfaceGrid g;
    std::vector<float> field;
    solver->BackendForTests()->Surface()->DownloadField(&g, &field);
    ASSERT_EQ(static_cast<int64_t>(field.size()), g.Samples());
    double worst = 0.0, peak = 0.0;
    CompareFieldWithBruteForce(g, field, fluid.position, w, volume, &worst, &peak);
    if (HasFatalFailure()) return;
    EXPECT_LT(worst, 1e-5 * std::max(1.0, peak));
    EXPECT_GT(peak, 0.9);
  }
}

}  // namespace
}  // namespace sphxr::test
