#pragma once
// HPMC on a thrust system: the launch side of surface_stages.h, one template for both backends
// (backend_impl.h owns one; backend_cpu.cpp and backend_cuda.cu instantiate it with their system).
// A build and a write read nothing back and wait for nothing: the lattice is the clamp box's (known on
// the host), the traversal is launched over the target's capacity with the vertex count left on the
// device, and the write's report (count, clamp) reaches the host through host-visible memory, read a
// frame later. Each launch, wait, allocation and copy back is counted (launch/counter.h).
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
#include "launch/counter.h"
#include "store/raw.h"
#include "surface_report.h"

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
  /// `source` re-grids the backend's particles (their grid is stale after a step) and returns them;
  /// `counter` is the backend's.
  SurfaceImpl(std::function<SurfaceParticles()> source, LaunchCounter* counter)
      : m_source(std::move(source)), m_counter(*counter) {
    const McTables& t = kMcTables;
    std::vector<uint32_t> word(256);
    for (int c = 0; c < 256; ++c) word[c] = t.vertexCount[c] | (static_cast<uint32_t>(c) << PyramidView::kCaseShift);
    m_baseWord.assign(word.begin(), word.end());
    m_edges.assign(&t.edges[0][0], &t.edges[0][0] + 256 * kMcMaxVertices);
    m_zero.assign(1, 0u);  // the apex of a lattice without cells
    for (int i = 0; i < 3; ++i) m_counter.Allocation();
  }

  Status BuildFromParticles(const SurfaceJob& job, SurfaceStats* stats) override {
    return GuardBackend(Traits::kName, "the surface", [&] { return BuildFromParticlesGuarded(job, stats); });
  }

  Status BuildFromParticlesGuarded(const SurfaceJob& job, SurfaceStats* stats) {
    const auto begin = Clock::now();
    auto policy = Traits::Policy();
    const SurfaceParticles p = m_source();
    SurfaceGrid grid;
    if (Status s = Lattice(LatticeBox(job, p), p.grid, &grid); !s) return s;
    const float cs = grid.cellSize;
    Resize(m_field, static_cast<size_t>(grid.Samples()));
    // Every sample is written by exactly one block of the field stage; NaN first makes a miss visible.
    thrust::fill(policy, m_field.begin(), m_field.end(), std::numeric_limits<float>::quiet_NaN());
    m_counter.Launch();

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
    m_counter.Launch();
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
    Resize(m_field, field.size());
    thrust::copy(field.begin(), field.end(), m_field.begin());
    return BuildPyramid(grid, isoLevel, begin, stats);
  }

  SurfaceWriteReport LastWrite() const override {
    const volatile DeviceWriteReport* r = m_report.Host();
    SurfaceWriteReport out;
    if (!r) return out;
    for (;;) {  // the write's number is stored last: equal before and after, the counts are that write's
      const int64_t write = r->write;
      out.vertices = r->vertices;
      out.written = r->written;
      out.capacity = r->capacity;
      if (r->write == write) {
        out.write = static_cast<uint64_t>(write);
        return out.write == 0 ? SurfaceWriteReport{} : out;
      }
    }
  }

  void SetTraversalRun(int vertices) override { m_traversalRun = vertices > 0 ? vertices : Traits::kTraversalRun; }

  Status WriteTo(const SurfaceTarget& target, SurfaceStats* stats) override {
    if (target.capacity < 0 || (target.capacity > 0 && (!target.positions || !target.normals))) {
      return Status::Error(Format("surface: a target of %lld vertices without its buffers",
                                  static_cast<long long>(target.capacity)));
    }
    return GuardBackend(Traits::kName, "the surface", [&] {
      if (Status s = Traverse(target.positions, target.normals, target.capacity, target.drawCommand, stats); !s) return s;
      Reported(stats);
      return Status::Ok();
    });
  }

  Status WriteOwned(SurfaceMeshView* view, SurfaceStats* stats) override {
    return GuardBackend(Traits::kName, "the surface", [&] { return WriteOwnedGuarded(view, stats); });
  }

  void DownloadMesh(SurfaceMesh* out) const override {
    out->positions.resize(static_cast<size_t>(3 * m_written));
    out->normals.resize(static_cast<size_t>(3 * m_written));
    if (m_written == 0) return;  // (thrust's host copy of nothing dereferences a null begin: UB)
    thrust::copy(m_positions.begin(), m_positions.begin() + 3 * m_written, out->positions.begin());
    thrust::copy(m_normals.begin(), m_normals.begin() + 3 * m_written, out->normals.begin());
    for (int copy = 0; copy < 2; ++copy) {  // the mesh, asked for by its reader (a host copy)
      m_counter.Download(/*asked=*/true);
      m_counter.Sync();
    }
  }

  void DownloadField(SurfaceGrid* grid, std::vector<float>* field) const override {
    *grid = m_grid;
    field->resize(m_field.size());
    thrust::copy(m_field.begin(), m_field.end(), field->begin());
    m_counter.Download(/*asked=*/true);
    m_counter.Sync();
  }

 private:
  FieldView Field(const SurfaceGrid& grid, float iso) const {
    return FieldView{grid.origin, grid.cellSize, 0.5f / grid.cellSize, grid.nx, grid.ny, grid.nz, iso, Raw(m_field)};
  }

  /// A vector resized, counted as an allocation when it outgrows what it holds.
  template <class T>
  void Resize(Vector<T>& v, size_t n) {
    if (n > v.capacity()) m_counter.Allocation();
    v.resize(n);
  }

  /// The box the lattice covers: the clamp box; on a backend whose particles are host memory
  /// (kSurfaceOverParticles: reading them costs no wait), the particles' bounding box within it, so the
  /// lattice follows the water instead of sampling the empty tank. Same lattice lines either way.
  static SurfaceJob LatticeBox(const SurfaceJob& job, const SurfaceParticles& p) {
    SurfaceJob box = job;
    if constexpr (Traits::kSurfaceOverParticles) {
      if (p.count == 0) return box;
      const Bounds b = thrust::transform_reduce(Traits::Policy(), thrust::counting_iterator<int>(0),
                                                thrust::counting_iterator<int>(p.count), BoundsOfPoint{p.position},
                                                Bounds{}, BoundsCombine{});
      const bool finite = std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) &&
                          std::isfinite(b.max.x) && std::isfinite(b.max.y) && std::isfinite(b.max.z);
      if (!finite) return box;  // a non-finite particle: the clamp box, as on the other backends
      box.boxMin = Vec3{std::max(job.boxMin.x, b.min.x), std::max(job.boxMin.y, b.min.y), std::max(job.boxMin.z, b.min.z)};
      box.boxMax = Vec3{std::min(job.boxMax.x, b.max.x), std::min(job.boxMax.y, b.max.y), std::min(job.boxMax.z, b.max.z)};
      if (!(box.boxMin.x <= box.boxMax.x && box.boxMin.y <= box.boxMax.y && box.boxMin.z <= box.boxMax.z)) return job;
    }
    return box;
  }

  /// The lattice: the clamp box plus the margin, on lattice lines through the neighbour grid's origin
  /// (a surface at rest does not move between frames). From the scene alone, so it is known on the host
  /// without reading the particles, and keeps its size from frame to frame.
  static Status Lattice(const SurfaceJob& job, const GridView& neighbours, SurfaceGrid* grid) {
    const float cs = job.cellSize;
    const float lo[3] = {job.boxMin.x - job.margin, job.boxMin.y - job.margin, job.boxMin.z - job.margin};
    const float hi[3] = {job.boxMax.x + job.margin, job.boxMax.y + job.margin, job.boxMax.z + job.margin};
    const float origin[3] = {neighbours.origin.x, neighbours.origin.y, neighbours.origin.z};
    double first[3], extent[3];
    for (int a = 0; a < 3; ++a) {
      first[a] = std::floor((static_cast<double>(lo[a]) - origin[a]) / cs);
      const double last = std::ceil((static_cast<double>(hi[a]) - origin[a]) / cs);
      extent[a] = last - first[a] + 1.0;
    }
    // In double, and checked before any cast.
    const double samples = extent[0] * extent[1] * extent[2];
    if (!(extent[0] >= 1.0 && extent[1] >= 1.0 && extent[2] >= 1.0)) {
      return Status::Error("surface: the tank's box is empty or not finite");
    }
    if (samples > static_cast<double>(job.maxSamples)) {
      return Status::Error(Format("surface: cell size %g m over the tank's %.3g x %.3g x %.3g m box needs %.3g field "
                                  "samples, above the limit of %lld: use a larger surface.cell_size",
                                  cs, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], samples,
                                  static_cast<long long>(job.maxSamples)));
    }
    grid->cellSize = cs;
    grid->origin = Vec3{origin[0] + static_cast<float>(first[0] * cs), origin[1] + static_cast<float>(first[1] * cs),
                        origin[2] + static_cast<float>(first[2] * cs)};
    grid->nx = static_cast<int>(extent[0]);
    grid->ny = static_cast<int>(extent[1]);
    grid->nz = static_cast<int>(extent[2]);
    return Status::Ok();
  }

  /// Levels: 0 = one node per cell; each level above halves every dimension (rounding up) until 1x1x1
  /// (at least two levels: the base and the apex). Launched only: the apex stays on the device.
  Status BuildPyramid(const SurfaceGrid& grid, float iso, Clock::time_point begin, SurfaceStats* stats) {
    auto policy = Traits::Policy();
    const auto fieldDone = Clock::now();
    m_grid = grid;
    m_iso = iso;
    m_pyramid = PyramidView{};
    m_apex = Raw(m_zero);
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
      Resize(m_nodes, static_cast<size_t>(total));
      if (m_sentinelAt != cells) {  // the upper levels never overwrite it: written when the lattice changes
        thrust::fill_n(policy, m_nodes.begin() + cells, 1, 0u);
        m_counter.Launch();
        m_sentinelAt = cells;
      }
      m_pyramid.count = Raw(m_nodes);
      const FieldView f = Field(grid, iso);
      // The base and level 1 in one pass over the field, then one launch per level up to the apex.
      const int top = m_pyramid.levels - 1;
      const int* b1 = m_pyramid.bricks[1];
      const int segments = (b1[0] + BaseLevelStage::kSegment - 1) / BaseLevelStage::kSegment;
      thrust::for_each_n(policy, thrust::counting_iterator<int>(0), segments * b1[1] * b1[2],
                         BaseLevelStage{f, m_pyramid, Raw(m_baseWord), segments});
      m_counter.Launch();
      for (int level = 2; level <= top; ++level) {
        const int* b = m_pyramid.bricks[level];
        thrust::for_each_n(policy, thrust::counting_iterator<int>(0), b[0] * b[1] * b[2],
                           ReduceLevelStage{m_pyramid, level});
        m_counter.Launch();
      }
      m_apex = Raw(m_nodes) + m_pyramid.offset[top] + 7;  // the apex: its brick's last sum
      stats->baseBytes = cells * static_cast<int64_t>(sizeof(uint32_t));
      stats->pyramidBytes = total * static_cast<int64_t>(sizeof(uint32_t));
    }
    const auto pyramidDone = Clock::now();
    stats->grid = grid;
    stats->pyramidLevels = m_pyramid.levels;
    stats->fieldBytes = static_cast<int64_t>(m_field.size() * sizeof(float));
    stats->capacity = m_capacity;
    stats->fieldSeconds = std::chrono::duration<double>(fieldDone - begin).count();
    stats->pyramidSeconds = std::chrono::duration<double>(pyramidDone - fieldDone).count();
    Reported(stats);
    return Status::Ok();
  }

  /// The last write's report into the stats (no copy, no wait: see surface_report.h).
  void Reported(SurfaceStats* stats) const {
    const SurfaceWriteReport r = LastWrite();
    stats->vertices = r.vertices;
    stats->triangles = r.vertices / 3;
    stats->clamped = r.Clamped();
  }

  /// The traversal over `capacity` vertices of the target (whole triangles): items past the apex return.
  Status Traverse(float* positions, float* normals, int64_t capacity, uint32_t* drawCommand, SurfaceStats* stats) {
    const auto begin = Clock::now();
    if (!m_reportReady) {
      if (Status s = m_report.Init(); !s) return s;
      m_counter.Allocation();
      m_reportReady = true;
    }
    const int64_t items = std::max<int64_t>(1, (capacity + m_traversalRun - 1) / m_traversalRun);
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int64_t>(0), items,
                       TraverseStage{Field(m_grid, m_iso), m_pyramid, Raw(m_edges), positions, normals, m_apex, capacity,
                                     m_traversalRun, m_report.Device(), ++m_writes, drawCommand});
    m_counter.Launch();
    stats->traversalSeconds += std::chrono::duration<double>(Clock::now() - begin).count();
    return Status::Ok();
  }

  /// Into the own buffer, for a reader that wants the mesh on the host side of the count: one wait, then
  /// the report; a mesh that did not fit grows the buffer (logged) and is written again, so the view is
  /// always the whole mesh.
  Status WriteOwnedGuarded(SurfaceMeshView* view, SurfaceStats* stats) {
    if (Status s = Traverse(Raw(m_positions), Raw(m_normals), m_capacity, nullptr, stats); !s) return s;
    if (Status s = Traits::Sync("surface traversal"); !s) return s;
    m_counter.Sync();
    const SurfaceWriteReport r = LastWrite();
    if (r.Clamped()) {
      // Geometric growth: a surface that keeps growing costs O(log) reallocations, each logged.
      int64_t grown = std::max<int64_t>({r.vertices + r.vertices / 4, m_capacity + m_capacity / 2, 3 * 4096});
      grown += (3 - grown % 3) % 3;
      SPHXR_LOG_INFO("surface: mesh buffer grown from %lld to %lld vertices (%.1f MiB) for a mesh of %lld triangles",
                     static_cast<long long>(m_capacity), static_cast<long long>(grown),
                     2.0 * 12.0 * static_cast<double>(grown) / 1048576.0, static_cast<long long>(r.vertices / 3));
      Vector<float>(static_cast<size_t>(3 * grown)).swap(m_positions);
      Vector<float>(static_cast<size_t>(3 * grown)).swap(m_normals);
      m_counter.Allocation();
      m_counter.Allocation();
      m_capacity = grown;
      stats->grew = true;
      if (Status s = Traverse(Raw(m_positions), Raw(m_normals), m_capacity, nullptr, stats); !s) return s;
    }
    stats->capacity = m_capacity;
    stats->vertices = r.vertices;
    stats->triangles = r.vertices / 3;
    stats->clamped = false;
    m_written = r.vertices;
    view->positions = Raw(m_positions);
    view->normals = Raw(m_normals);
    view->vertexCount = m_written;
    view->onDevice = Traits::kOnDevice;
    return Status::Ok();
  }

  std::function<SurfaceParticles()> m_source;
  LaunchCounter& m_counter;
  Vector<uint32_t> m_baseWord;    // per case: vertex count | case << kCaseShift, on this system
  Vector<int8_t> m_edges;
  Vector<uint32_t> m_zero;        // one 0: the apex when the lattice has no cells
  Vector<float> m_field;
  Vector<uint32_t> m_nodes;       // every pyramid level, base first
  int64_t m_sentinelAt = -1;      // where the base level's zero sentinel was written
  PyramidView m_pyramid{};
  const uint32_t* m_apex = nullptr;  // the mesh's vertex count, on the device
  SurfaceGrid m_grid;
  float m_iso = 0.5f;
  HostVisibleReport<Traits::kOnDevice> m_report;  // the last write's count and clamp
  bool m_reportReady = false;
  uint64_t m_writes = 0;          // writes launched (the report's numbers)
  int64_t m_written = 0;          // vertices in the own buffer
  int64_t m_capacity = 0;         // vertices the own buffer holds (a multiple of 3)
  int m_traversalRun = Traits::kTraversalRun;  // vertices per traversal work item
  Vector<float> m_positions, m_normals;
};

}  // namespace sphxr::sim
