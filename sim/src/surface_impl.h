#pragma once
// HPMC on a thrust system: the launch side of surface_stages.h, one template for both backends
// (backend_impl.h owns one; backend_cpu.cpp and backend_cuda.cu instantiate it with their system).
#include <thrust/copy.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

#include "sphxr/common/log.h"
#include "backend_guard.h"
#include "surface_extractor.h"
#include "surface_stages.h"
#include "store/raw.h"

namespace sphxr::sim {

/// The particles as the field stage reads them: sorted positions and a neighbour grid built for them.
struct SurfaceParticles {
  const Vec4* position;
  int count;
  GridView grid;
};

template <class Traits>
class SurfaceImpl final : public SurfaceExtractor {
  template <class T>
  using Vector = typename Traits::template Vector<T>;
  using Clock = std::chrono::steady_clock;

 public:
  /// `source` re-grids the backend's particles (their grid is stale after a step) and returns them.
  explicit SurfaceImpl(std::function<SurfaceParticles()> source) : m_source(std::move(source)) {
    const McTables& t = kMcTables;
    std::vector<uint32_t> word(256);
    for (int c = 0; c < 256; ++c) word[c] = t.vertexCount[c] | (static_cast<uint32_t>(c) << PyramidView::kCaseShift);
    m_baseWord.assign(word.begin(), word.end());
    m_edges.assign(&t.edges[0][0], &t.edges[0][0] + 256 * kMcMaxVertices);
  }

  Status BuildFromParticles(const SurfaceJob& job, SurfaceStats* stats) override {
    return GuardBackend(Traits::kName, "the surface", [&] { return BuildFromParticlesGuarded(job, stats); });
  }

  Status BuildFromParticlesGuarded(const SurfaceJob& job, SurfaceStats* stats) {
    const auto begin = Clock::now();
    auto policy = Traits::Policy();
    const SurfaceParticles p = m_source();
    SurfaceGrid grid;
    grid.cellSize = job.cellSize;
    if (p.count == 0) {
      m_field.clear();
      return BuildPyramid(grid, job.isoLevel, begin, stats);
    }
    const Bounds b = thrust::transform_reduce(policy, thrust::counting_iterator<int>(0),
                                              thrust::counting_iterator<int>(p.count), BoundsOfPoint{p.position},
                                              Bounds{}, BoundsCombine{});
    // The lattice covers the bounding box plus the margin, on lattice lines through the neighbour grid's
    // origin: a surface at rest does not move when the bounding box does.
    const float cs = job.cellSize;
    const float lo[3] = {b.min.x - job.margin, b.min.y - job.margin, b.min.z - job.margin};
    const float hi[3] = {b.max.x + job.margin, b.max.y + job.margin, b.max.z + job.margin};
    const float origin[3] = {p.grid.origin.x, p.grid.origin.y, p.grid.origin.z};
    double first[3], extent[3];
    for (int a = 0; a < 3; ++a) {
      first[a] = std::floor((static_cast<double>(lo[a]) - origin[a]) / cs);
      const double last = std::ceil((static_cast<double>(hi[a]) - origin[a]) / cs);
      extent[a] = last - first[a] + 1.0;
    }
    // In double, and checked before any cast: bounds that are not finite numbers give no lattice.
    const double samples = extent[0] * extent[1] * extent[2];
    if (!(extent[0] >= 1.0 && extent[1] >= 1.0 && extent[2] >= 1.0)) {  // (each axis: two inverted ones multiply to > 0)
      return Status::Error("surface: the particles' bounding box is not finite (a non-finite position?)");
    }
    if (samples > static_cast<double>(job.maxSamples)) {
      return Status::Error(Format("surface: cell size %g m over the fluid's %.3g x %.3g x %.3g m bounding box needs "
                                  "%.3g field samples, above the limit of %lld: use a larger surface.cell_size",
                                  cs, b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z, samples,
                                  static_cast<long long>(job.maxSamples)));
    }
    grid.origin = Vec3{origin[0] + static_cast<float>(first[0] * cs), origin[1] + static_cast<float>(first[1] * cs),
                       origin[2] + static_cast<float>(first[2] * cs)};
    grid.nx = static_cast<int>(extent[0]);
    grid.ny = static_cast<int>(extent[1]);
    grid.nz = static_cast<int>(extent[2]);
    m_field.resize(static_cast<size_t>(grid.Samples()));
    // Every sample is written by exactly one block of the field stage; NaN first makes a miss visible.
    thrust::fill(policy, m_field.begin(), m_field.end(), std::numeric_limits<float>::quiet_NaN());

    // Blocks of B^3 neighbour-grid cells under the lattice: B as large as keeps a block within
    // FieldStage::kMaxBlock samples per axis (a cell holds up to ceil(ratio) + 1 samples per axis).
    int c0[3], c1[3];
    p.grid.CellOf(grid.origin, &c0[0], &c0[1], &c0[2]);
    p.grid.CellOf(grid.origin + Vec3{(grid.nx - 1) * cs, (grid.ny - 1) * cs, (grid.nz - 1) * cs}, &c1[0], &c1[1], &c1[2]);
    const int perCell = static_cast<int>(std::ceil(p.grid.cellSize / cs));
    const int block = std::max(1, (FieldStage::kMaxBlock - 1) / std::max(1, perCell));
    int blocks[3];
    for (int a = 0; a < 3; ++a) blocks[a] = (c1[a] - c0[a]) / block + 1;
    const FieldView f = Field(grid, job.isoLevel);
    thrust::for_each_n(policy, thrust::counting_iterator<int>(0), blocks[0] * blocks[1] * blocks[2],
                       FieldStage{p.grid, p.position, job.kernel, job.volume, f, c0[0], c0[1], c0[2], c1[0], c1[1],
                                  c1[2], block, blocks[0], blocks[1], Raw(m_field)});
    return BuildPyramid(grid, job.isoLevel, begin, stats);
  }

  Status BuildFromField(const SurfaceGrid& grid, const std::vector<float>& field, float isoLevel,
                        SurfaceStats* stats) override {
    const auto begin = Clock::now();
    if (static_cast<int64_t>(field.size()) != grid.Samples()) {
      return Status::Error(Format("surface: %zu field values for a %d x %d x %d lattice", field.size(), grid.nx,
                                  grid.ny, grid.nz));
    }
    // 2^27 as for particles (kMaxSurfaceSamples): the pyramid's offsets and level sums are 32-bit.
    if (grid.nx < 1 || grid.ny < 1 || grid.nz < 1 || grid.Samples() > (int64_t{1} << 27) || !(grid.cellSize > 0.0f)) {
      return Status::Error("surface: the lattice must have 1 to 2^27 samples (at least 1 per axis) and a positive cell size");
    }
    m_field.assign(field.begin(), field.end());
    return BuildPyramid(grid, isoLevel, begin, stats);
  }

  int64_t VertexCount() const override { return m_vertices; }

  void SetTraversalRun(int vertices) override { m_traversalRun = vertices > 0 ? vertices : Traits::kTraversalRun; }

  Status WriteTo(const SurfaceTarget& target, SurfaceStats* stats) override {
    if (target.capacity < m_vertices) {
      return Status::Error(Format("surface: the mesh has %lld vertices, the target holds %lld: grow it and write again",
                                  static_cast<long long>(m_vertices), static_cast<long long>(target.capacity)));
    }
    return GuardBackend(Traits::kName, "the surface", [&] { return Traverse(target.positions, target.normals, stats); });
  }

  Status WriteOwned(SurfaceMeshView* view, SurfaceStats* stats) override {
    if (m_vertices > m_capacity) {
      // Geometric growth: a surface that keeps growing costs O(log) reallocations, each logged.
      const int64_t grown = std::max<int64_t>({m_vertices + m_vertices / 4, m_capacity + m_capacity / 2, 3 * 4096});
      SPHXR_LOG_INFO("surface: mesh buffer grown from %lld to %lld vertices (%.1f MiB) for a mesh of %lld triangles",
                     static_cast<long long>(m_capacity), static_cast<long long>(grown),
                     2.0 * 12.0 * static_cast<double>(grown) / 1048576.0, static_cast<long long>(m_vertices / 3));
      Vector<float>(static_cast<size_t>(3 * grown)).swap(m_positions);
      Vector<float>(static_cast<size_t>(3 * grown)).swap(m_normals);
      m_capacity = grown;
      stats->grew = true;
    }
    stats->capacity = m_capacity;
    if (Status s = GuardBackend(Traits::kName, "the surface", [&] { return Traverse(Raw(m_positions), Raw(m_normals), stats); });
        !s) {
      return s;
    }
    m_written = m_vertices;
    view->positions = Raw(m_positions);
    view->normals = Raw(m_normals);
    view->vertexCount = m_vertices;
    view->onDevice = Traits::kOnDevice;
    return Status::Ok();
  }

  void DownloadMesh(SurfaceMesh* out) const override {
    out->positions.resize(static_cast<size_t>(3 * m_written));
    out->normals.resize(static_cast<size_t>(3 * m_written));
    if (m_written == 0) return;  // (thrust's host copy of nothing dereferences a null begin: UB)
    thrust::copy(m_positions.begin(), m_positions.begin() + 3 * m_written, out->positions.begin());
    thrust::copy(m_normals.begin(), m_normals.begin() + 3 * m_written, out->normals.begin());
  }

  void DownloadField(SurfaceGrid* grid, std::vector<float>* field) const override {
    *grid = m_grid;
    field->resize(m_field.size());
    thrust::copy(m_field.begin(), m_field.end(), field->begin());
  }

 private:
  FieldView Field(const SurfaceGrid& grid, float iso) const {
    return FieldView{grid.origin, grid.cellSize, 0.5f / grid.cellSize, grid.nx, grid.ny, grid.nz, iso, Raw(m_field)};
  }

  /// Levels: 0 = one node per cell; each level above halves every dimension (rounding up) until 1x1x1
  /// (at least two levels: the base and the apex).
  Status BuildPyramid(const SurfaceGrid& grid, float iso, Clock::time_point begin, SurfaceStats* stats) {
    auto policy = Traits::Policy();
    if (Status s = Traits::Sync("surface field"); !s) return s;
    const auto fieldDone = Clock::now();
    m_grid = grid;
    m_iso = iso;
    m_vertices = 0;
    m_pyramid = PyramidView{};
    const int64_t cells = grid.Cells();
    if (cells > 0) {
      int d[3] = {grid.nx - 1, grid.ny - 1, grid.nz - 1};
      int64_t total = cells + 1;  // the base level and its sentinel
      m_pyramid.offset[0] = 0;
      m_pyramid.sentinel = static_cast<int>(cells);
      for (int level = 0;; ++level) {
        if (level == kMaxPyramidLevels) return Status::Error("surface: too many pyramid levels");
        for (int a = 0; a < 3; ++a) {
          m_pyramid.dims[level][a] = d[a];
          m_pyramid.bricks[level][a] = (d[a] + 1) / 2;
        }
        if (level > 0) {
          m_pyramid.offset[level] = static_cast<int>(total);
          total += 8 * static_cast<int64_t>(m_pyramid.bricks[level][0]) * m_pyramid.bricks[level][1] *
                   m_pyramid.bricks[level][2];
        }
        m_pyramid.levels = level + 1;
        if (level > 0 && d[0] == 1 && d[1] == 1 && d[2] == 1) break;  // a single cell still gets a level 1
        for (int& x : d) x = (x + 1) / 2;
      }
      m_nodes.resize(static_cast<size_t>(total));
      m_nodes[static_cast<size_t>(cells)] = 0;
      m_pyramid.count = Raw(m_nodes);
      const FieldView f = Field(grid, iso);
      // The base and level 1 in one pass over the field, then one launch per level up to the apex.
      const int top = m_pyramid.levels - 1;
      const int* b1 = m_pyramid.bricks[1];
      const int segments = (b1[0] + BaseLevelStage::kSegment - 1) / BaseLevelStage::kSegment;
      thrust::for_each_n(policy, thrust::counting_iterator<int>(0), segments * b1[1] * b1[2],
                         BaseLevelStage{f, m_pyramid, Raw(m_baseWord), segments});
      for (int level = 2; level <= top; ++level) {
        const int* b = m_pyramid.bricks[level];
        thrust::for_each_n(policy, thrust::counting_iterator<int>(0), b[0] * b[1] * b[2],
                           ReduceLevelStage{m_pyramid, level});
      }
      m_vertices = m_nodes[static_cast<size_t>(m_pyramid.offset[top] + 7)];  // the apex: its brick's last sum
      stats->baseBytes = cells * static_cast<int64_t>(sizeof(uint32_t));
      stats->pyramidBytes = total * static_cast<int64_t>(sizeof(uint32_t));
    }
    if (Status s = Traits::Sync("surface pyramid"); !s) return s;
    const auto pyramidDone = Clock::now();
    stats->grid = grid;
    stats->vertices = m_vertices;
    stats->triangles = m_vertices / 3;
    stats->pyramidLevels = m_pyramid.levels;
    stats->fieldBytes = static_cast<int64_t>(m_field.size() * sizeof(float));
    stats->capacity = m_capacity;
    stats->fieldSeconds = std::chrono::duration<double>(fieldDone - begin).count();
    stats->pyramidSeconds = std::chrono::duration<double>(pyramidDone - fieldDone).count();
    return Status::Ok();
  }

  Status Traverse(float* positions, float* normals, SurfaceStats* stats) {
    const auto begin = Clock::now();
    if (m_vertices > 0) {
      const int64_t items = (m_vertices + m_traversalRun - 1) / m_traversalRun;
      thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int64_t>(0), items,
                         TraverseStage{Field(m_grid, m_iso), m_pyramid, Raw(m_edges), positions, normals, m_vertices,
                                       m_traversalRun});
    }
    if (Status s = Traits::Sync("surface traversal"); !s) return s;
    stats->traversalSeconds = std::chrono::duration<double>(Clock::now() - begin).count();
    return Status::Ok();
  }

  std::function<SurfaceParticles()> m_source;
  Vector<uint32_t> m_baseWord;    // per case: vertex count | case << kCaseShift, on this system
  Vector<int8_t> m_edges;
  Vector<float> m_field;
  Vector<uint32_t> m_nodes;       // every pyramid level, base first
  PyramidView m_pyramid{};
  SurfaceGrid m_grid;
  float m_iso = 0.5f;
  int64_t m_vertices = 0;         // apex of the last build
  int64_t m_written = 0;          // vertices in the own buffer
  int64_t m_capacity = 0;         // vertices the own buffer holds
  int m_traversalRun = Traits::kTraversalRun;  // vertices per traversal work item
  Vector<float> m_positions, m_normals;
};

}  // namespace sphxr::sim
