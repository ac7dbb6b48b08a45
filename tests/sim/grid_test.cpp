// The neighbour grid of the CPU backend (stages 1-3: cell codes, stable sort + reorder, cell ranges),
// driven through Solver::BackendForTests()->RebuildGrid on particle sets placed with Solver::Upload.
// Truth: brute-force O(n^2) neighbour lists, and the uploaded values of every field (by id).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "backend.h"
#include "morton.h"
#include "support.h"

namespace sphxr::sim {
namespace {

constexpr uint32_t kIdBase = 1000;
constexpr uint32_t kIdStride = 3;
uint32_t IdOf(size_t index) { return kIdBase + kIdStride * static_cast<uint32_t>(index); }
size_t IndexOfId(uint32_t id) { return (id - kIdBase) / kIdStride; }

struct CellCoord {
  int x, y, z;
};

// The cell lookup, reimplemented from GridInfo: floor((p - origin) / cellSize) per axis in float (as the
// backend computes it, with the reciprocal), clamped to the grid.
CellCoord CellOf(const Solver::GridInfo& g, Vec3 p) {
  const float inv = 1.0f / g.cellSize;
  auto axis = [&](float v, float o, int n) {
    const float c = std::floor(std::max(0.0f, std::min((v - o) * inv, 1e9f)));
    return std::clamp(static_cast<int>(c), 0, n - 1);
  };
  return {axis(p.x, g.origin.x, g.dims[0]), axis(p.y, g.origin.y, g.dims[1]), axis(p.z, g.origin.z, g.dims[2])};
}

size_t Linear(const Solver::GridInfo& g, CellCoord c) {
  return static_cast<size_t>(c.x) + static_cast<size_t>(g.dims[0]) * (c.y + static_cast<size_t>(g.dims[1]) * c.z);
}

// Distinct, recognisable values for a field of type T (field number `f`, particle `i`).
template <class T>
T MakeValue(size_t i, int f) {
  const float fi = static_cast<float>(i);
  if constexpr (std::is_same_v<T, Vec4>) {
    return Vec4{fi + 0.25f + 1000.0f * f, -fi - 0.5f * f, 0.125f * fi + 7.0f * f, 3.0f * fi - f};
  } else if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(0.75 * static_cast<double>(i) + 10000.0 * f + 0.5);
  } else if constexpr (std::is_integral_v<T>) {
    return static_cast<T>(i * 13 + 100000 * static_cast<size_t>(f) + 1);
  } else {
    static_assert(std::is_same_v<T, void>, "grid_test: add a MakeValue for this field type");
  }
}

bool IsEmpty(uint32_t start) { return start == kEmptyCell; }

class GridTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // 10 x 10 x 10 = 1000 fluid particles in a 0.3 m tank; cells of 2 dx = 0.02 m.
    test::SceneSetup scene = test::TankScene({0, 0, 0}, {0.3f, 0.3f, 0.3f}, 0.01f);
    scene.fluid.push_back(test::Block({0.1f, 0.1f, 0.1f}, {0.2f, 0.2f, 0.2f}));
    m_solver = test::CreateOrFail(scene);
    ASSERT_TRUE(m_solver);
    m_n = static_cast<size_t>(m_solver->FluidCount());
    ASSERT_EQ(m_n, 1000u);
    m_grid = m_solver->Grid();
    m_H = m_solver->SupportRadius();
  }

  /// Uploads `positions` with every other field set to values derived from the index, rebuilds the
  /// grid and checks everything; `what` names the particle set in failures.
  void Check(const std::vector<Vec3>& positions, const std::string& what) {
    ASSERT_EQ(positions.size(), m_n);
    HostFluid before;
    before.resize(m_n);
    int field = 0;
#define SPHXR_FILL_FIELD(type, name)                                                  \
  ++field;                                                                            \
  for (size_t i = 0; i < m_n; ++i) before.name[i] = MakeValue<type>(i, field);
    SPHXR_FLUID_FIELDS(SPHXR_FILL_FIELD)
#undef SPHXR_FILL_FIELD
    for (size_t i = 0; i < m_n; ++i) {
      before.position[i] = MakeVec4(positions[i], before.position[i].w);
      before.id[i] = IdOf(i);
    }
    ASSERT_TRUE(m_solver->Upload(before).ok());

    std::vector<uint32_t> start, end;
    m_solver->BackendForTests()->RebuildGrid(&start, &end);
    HostFluid after;
    m_solver->Download(&after);
    ASSERT_EQ(after.size(), m_n) << what;
    const size_t cells = static_cast<size_t>(m_grid.dims[0]) * m_grid.dims[1] * m_grid.dims[2];
    ASSERT_EQ(start.size(), cells) << what;
    ASSERT_EQ(end.size(), cells) << what;

    // 1. The sort is a permutation that keeps every field of every particle (matched by id).
    std::vector<int> seen(m_n, 0);
    for (size_t k = 0; k < m_n; ++k) {
      const uint32_t id = after.id[k];
      ASSERT_TRUE(id >= kIdBase && (id - kIdBase) % kIdStride == 0 && IndexOfId(id) < m_n)
          << what << ": unknown id " << id << " at sorted index " << k;
      ++seen[IndexOfId(id)];
    }
    for (size_t i = 0; i < m_n; ++i) ASSERT_EQ(seen[i], 1) << what << ": id " << IdOf(i) << " appears " << seen[i] << " times";
#define SPHXR_COMPARE_FIELD(type, name)                                                                     \
  {                                                                                                         \
    int mismatches = 0;                                                                                     \
    size_t first = 0;                                                                                       \
    for (size_t k = 0; k < m_n; ++k) {                                                                      \
      const size_t orig = IndexOfId(after.id[k]);                                                           \
      if (std::memcmp(&after.name[k], &before.name[orig], sizeof(type)) != 0 && mismatches++ == 0) first = k; \
    }                                                                                                       \
    EXPECT_EQ(mismatches, 0) << what << ": field '" #name "' changed by the sort for " << mismatches          \
                             << " particles, first at sorted index " << first << " (id " << after.id[first] << ")"; \
  }
    SPHXR_FLUID_FIELDS(SPHXR_COMPARE_FIELD)
#undef SPHXR_COMPARE_FIELD

    // 2. Sorted by the Morton code of the cell, stable (ids ascend within one cell).
    std::vector<CellCoord> cell(m_n);
    std::vector<uint32_t> code(m_n);
    for (size_t k = 0; k < m_n; ++k) {
      cell[k] = CellOf(m_grid, Xyz(after.position[k]));
      code[k] = MortonEncode(cell[k].x, cell[k].y, cell[k].z);
      if (k > 0) {
        ASSERT_LE(code[k - 1], code[k]) << what << ": not sorted by Morton code at sorted index " << k;
        if (code[k - 1] == code[k]) {
          ASSERT_LT(after.id[k - 1], after.id[k]) << what << ": sort not stable within a cell at sorted index " << k;
        }
      }
    }

    // 3. Cell ranges: each particle lies in its own cell's range; the ranges partition [0, n).
    size_t covered = 0;
    for (size_t c = 0; c < cells; ++c) {
      if (IsEmpty(start[c])) continue;
      ASSERT_LT(start[c], end[c]) << what << ": empty range of cell " << c;
      ASSERT_LE(end[c], m_n) << what;
      covered += end[c] - start[c];
      for (uint32_t j = start[c]; j < end[c]; ++j) {
        ASSERT_EQ(Linear(m_grid, cell[j]), c) << what << ": particle at sorted index " << j << " is in the range of cell "
                                              << c << " but lies in cell " << Linear(m_grid, cell[j]);
      }
    }
    EXPECT_EQ(covered, m_n) << what << ": cell ranges do not cover every particle exactly once";
    for (size_t k = 0; k < m_n; ++k) {
      const size_t c = Linear(m_grid, cell[k]);
      ASSERT_FALSE(IsEmpty(start[c])) << what << ": cell " << c << " of particle " << k << " marked empty";
      ASSERT_TRUE(start[c] <= k && k < end[c]) << what << ": particle " << k << " outside its cell's range";
    }

    // 4. Neighbours through the 27 cells == brute force within the support radius.
    const float H2 = m_H * m_H;
    auto within = [&](size_t i, size_t j) {
      const Vec4 a = after.position[i], b = after.position[j];
      const Vec3 d{a.x - b.x, a.y - b.y, a.z - b.z};
      return Dot(d, d) < H2;
    };
    size_t totalPairs = 0;
    for (size_t i = 0; i < m_n; ++i) {
      std::vector<uint32_t> brute, viaGrid;
      for (size_t j = 0; j < m_n; ++j)
        if (within(i, j)) brute.push_back(static_cast<uint32_t>(j));
      const CellCoord ci = cell[i];
      for (int z = std::max(0, ci.z - 1); z <= std::min(m_grid.dims[2] - 1, ci.z + 1); ++z)
        for (int y = std::max(0, ci.y - 1); y <= std::min(m_grid.dims[1] - 1, ci.y + 1); ++y)
          for (int x = std::max(0, ci.x - 1); x <= std::min(m_grid.dims[0] - 1, ci.x + 1); ++x) {
            const size_t c = Linear(m_grid, {x, y, z});
            if (IsEmpty(start[c])) continue;
            for (uint32_t j = start[c]; j < end[c]; ++j)
              if (within(i, j)) viaGrid.push_back(j);
          }
      std::sort(viaGrid.begin(), viaGrid.end());
      totalPairs += brute.size();
      if (brute != viaGrid) {
        std::vector<uint32_t> missed;
        std::set_difference(brute.begin(), brute.end(), viaGrid.begin(), viaGrid.end(), std::back_inserter(missed));
        std::string detail;
        for (uint32_t j : missed) {
          const Vec4 a = after.position[i], b = after.position[j];
          detail += Format(" j=%u at [%.9g %.9g %.9g] (r/H = %.9g)", j, b.x, b.y, b.z,
                           std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)) / m_H);
        }
        ADD_FAILURE() << what << ": particle " << i << " (id " << after.id[i] << ") at [" << after.position[i].x << ", "
                      << after.position[i].y << ", " << after.position[i].z << "]: brute force finds " << brute.size()
                      << " neighbours, the grid " << viaGrid.size() << "; missed:" << detail;
        return;
      }
    }
    EXPECT_GT(totalPairs, m_n) << what << ": the particle set has too few neighbour pairs to test anything";
    RecordProperty(what + "_pairs", std::to_string(totalPairs));
  }

  std::unique_ptr<Solver> m_solver;
  size_t m_n = 0;
  Solver::GridInfo m_grid{};
  float m_H = 0.0f;
};

TEST_F(GridTest, CellsAreAtLeastTheSupportWide) {
  EXPECT_GE(m_grid.cellSize, m_H);
  // The grid covers the tank with its boundary layers.
  const Aabb tank = m_solver->Scene().tank;
  EXPECT_LT(m_grid.origin.x, tank.min.x - 0.5f * m_solver->Scene().params.spacing);
  EXPECT_GT(m_grid.origin.x + m_grid.dims[0] * m_grid.cellSize, tank.max.x + 0.5f * m_solver->Scene().params.spacing);
  EXPECT_GT(m_grid.origin.y + m_grid.dims[1] * m_grid.cellSize, tank.max.y);
  EXPECT_GT(m_grid.origin.z + m_grid.dims[2] * m_grid.cellSize, tank.max.z + 0.5f * m_solver->Scene().params.spacing);
}

TEST_F(GridTest, RandomParticles) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> tank(0.0f, 0.3f), dense(0.1f, 0.2f);
  std::vector<Vec3> p(m_n);
  for (size_t i = 0; i < m_n; ++i) {
    // half spread over the tank, half in a dense 0.1 m cube (about 30 neighbours each)
    if (i % 2) p[i] = {tank(rng), tank(rng), tank(rng)};
    else p[i] = {dense(rng), dense(rng), dense(rng)};
  }
  Check(p, "random");
}

TEST_F(GridTest, ClusteredInAFewCells) {
  std::mt19937 rng(99);
  // three cells: two face-adjacent, one two cells away diagonally
  const CellCoord chosen[3] = {{7, 7, 7}, {8, 7, 7}, {10, 9, 9}};
  std::uniform_real_distribution<float> u(0.001f, 0.999f);
  std::vector<Vec3> p(m_n);
  for (size_t i = 0; i < m_n; ++i) {
    const CellCoord c = chosen[i % 3];
    p[i] = {m_grid.origin.x + (c.x + u(rng)) * m_grid.cellSize, m_grid.origin.y + (c.y + u(rng)) * m_grid.cellSize,
            m_grid.origin.z + (c.z + u(rng)) * m_grid.cellSize};
  }
  // precondition: they really are in those cells
  for (size_t i = 0; i < m_n; ++i) {
    const CellCoord c = CellOf(m_grid, p[i]), want = chosen[i % 3];
    ASSERT_TRUE(c.x == want.x && c.y == want.y && c.z == want.z);
  }
  Check(p, "clustered");
}

TEST_F(GridTest, OnCellBoundaries) {
  // Coordinates exactly on cell boundaries (origin + k * cellSize, in float) around the tank centre:
  // a third of the particles on cell corners, a third on cell edges, a third on cell faces.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const CellCoord c0 = CellOf(m_grid, {0.15f, 0.15f, 0.15f});
  const float origin[3] = {m_grid.origin.x, m_grid.origin.y, m_grid.origin.z};
  const int centre[3] = {c0.x, c0.y, c0.z};
  std::vector<Vec3> p(m_n);
  for (size_t i = 0; i < m_n; ++i) {
    float c[3];
    for (int a = 0; a < 3; ++a) {
      const int k = centre[a] - 2 + static_cast<int>(rng() % 5);
      c[a] = origin[a] + static_cast<float>(k) * m_grid.cellSize;
    }
    const int kind = static_cast<int>(i % 3);  // 0 corner, 1 edge (z free), 2 face (y and z free)
    if (kind >= 1) c[2] += u(rng) * m_grid.cellSize;
    if (kind == 2) c[1] += u(rng) * m_grid.cellSize;
    p[i] = {c[0], c[1], c[2]};
  }
  Check(p, "cell-boundary");
}

TEST_F(GridTest, OnCellBoundariesDense) {
  // Every particle on a corner of the 4 x 4 x 4 cells around the tank centre: many coincident points
  // and exact-border pairs at exactly one cell size (= the support, not neighbours) apart.
  std::vector<Vec3> p(m_n);
  const CellCoord c0 = CellOf(m_grid, {0.15f, 0.15f, 0.15f});
  for (size_t i = 0; i < m_n; ++i) {
    const int k = static_cast<int>(i % 64);
    const CellCoord c{c0.x - 2 + k % 4, c0.y - 2 + (k / 4) % 4, c0.z - 2 + k / 16};
    p[i] = {m_grid.origin.x + c.x * m_grid.cellSize, m_grid.origin.y + c.y * m_grid.cellSize,
            m_grid.origin.z + c.z * m_grid.cellSize};
  }
  Check(p, "cell-corner-dense");
}

TEST_F(GridTest, InitialLatticeAndAfterSteps) {
  // The scene's own lattice, and the state after a few real steps of a falling block.
  HostFluid initial;
  m_solver->Download(&initial);
  std::vector<Vec3> p(m_n);
  for (size_t i = 0; i < m_n; ++i) p[i] = Xyz(initial.position[i]);
  Check(p, "lattice");
  ASSERT_TRUE(m_solver->Upload(initial).ok());  // Check() uploaded marker values in every field
  ASSERT_TRUE(test::StepN(*m_solver, 30));
  HostFluid h;
  m_solver->Download(&h);
  ASSERT_EQ(test::FirstNonFinite(h), "");
  for (size_t i = 0; i < m_n; ++i) p[i] = Xyz(h.position[i]);
  Check(p, "after-30-steps");
}

}  // namespace
}  // namespace sphxr::sim
