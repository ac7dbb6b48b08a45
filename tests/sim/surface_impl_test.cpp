// The surface's launches, waits, allocations and copies back (sim/src/surface_impl.h) on cpu-reference,
// which runs the CUDA backend's orchestration and counts what it would do: a build and a write into a
// renderer's buffer read nothing back and wait for nothing, a steady frame allocates nothing, and a
// buffer too small is clamped, reported, and grown for the next frame. Counts, not times.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "sphxr/sim/launch_counts.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/surface.h"
#include "support.h"

namespace sphxr::test {
namespace {

std::unique_ptr<sim::Solver> ReferenceDamBreak() {
  sim::SolverConfig config;
  config.device = sim::Device::kCpuReference;
  config.threads = 1;
  return CreateOrFail(SmallDamBreak(), config);
}

void Print(const char* what, const sim::LaunchCounts& c) {
  std::printf("[counts] %s: %lld launches, %lld waits, %lld allocations, %lld copies back\n", what,
              static_cast<long long>(c.launches), static_cast<long long>(c.syncs),
              static_cast<long long>(c.allocations), static_cast<long long>(c.downloads));
}

/// A renderer's mesh buffer: host memory on cpu-reference, where CUDA's would be mapped GL buffers.
struct Buffer {
  std::vector<float> positions, normals;
  uint32_t draw[4] = {0, 0, 0, 0};
  int64_t capacity = 0;
  void Grow(int64_t vertices) {
    capacity = vertices;
    positions.assign(static_cast<size_t>(3 * vertices), std::numeric_limits<float>::quiet_NaN());
    normals = positions;
  }
  sim::SurfaceTarget Target() { return {positions.data(), normals.data(), capacity, draw}; }
};

TEST(SurfaceImplCounts, BuildAndWriteReadNothingBackAndASteadyFrameAllocatesNothing) {
  auto solver = ReferenceDamBreak();
  ASSERT_TRUE(solver);
  Buffer buffer;
  buffer.Grow(30000);
  sim::LaunchCounts steady;
  for (int frame = 0; frame < 3; ++frame) {
    ASSERT_TRUE(StepN(*solver, 5));
    const sim::LaunchCounts before = solver->Counts();
    sim::SurfaceStats stats;
    ASSERT_TRUE(solver->BuildSurface(sim::SurfaceParams{}, &stats).ok());
    const sim::LaunchCounts built = solver->Counts();
    ASSERT_TRUE(solver->WriteSurface(buffer.Target(), &stats).ok());
    const sim::LaunchCounts frameCounts = solver->Counts() - before;
    SCOPED_TRACE(::testing::Message() << "frame " << frame);
    // Nothing read back, nothing waited for, before the draw.
    EXPECT_EQ(frameCounts.downloads, 0);
    EXPECT_EQ(frameCounts.syncs, 0);
    EXPECT_GT((built - before).launches, 3);
    EXPECT_EQ((solver->Counts() - built).launches, 1);  // the traversal (its item 0 reports)
    if (frame > 0) {
      EXPECT_EQ(frameCounts.allocations, 0);
      steady = frameCounts;
    }
    ASSERT_FALSE(solver->LastSurfaceWrite().Clamped()) << "30,000 vertices hold this mesh";
  }
  Print("BuildSurface + WriteSurface, steady frame", steady);
  // The draw command holds the count the host copy reads back.
  sim::SurfaceMesh mesh;
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh).ok());  // grows the solver's own buffer
  const sim::LaunchCounts before = solver->Counts();
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &mesh).ok());
  const sim::LaunchCounts extract = solver->Counts() - before;
  Print("ExtractSurface to a host copy, steady", extract);
  ASSERT_GT(mesh.TriangleCount(), 100);
  EXPECT_EQ(extract.downloads, 2);  // positions, normals: what the reader asked for
  EXPECT_EQ(extract.syncs, 3);      // the report's wait, and each blocking copy
  EXPECT_EQ(extract.allocations, 0);
  ASSERT_TRUE(solver->BuildSurface(sim::SurfaceParams{}, nullptr).ok());
  ASSERT_TRUE(solver->WriteSurface(buffer.Target(), nullptr).ok());
  EXPECT_EQ(buffer.draw[0], static_cast<uint32_t>(mesh.VertexCount()));
  EXPECT_EQ(buffer.draw[1], 1u);
  const std::vector<float> written(buffer.positions.begin(), buffer.positions.begin() + 3 * mesh.VertexCount());
  EXPECT_EQ(written, mesh.positions);
}

TEST(SurfaceImplCounts, AnOverflowIsClampedReportedAndGrownForTheNextFrame) {
  auto solver = ReferenceDamBreak();
  ASSERT_TRUE(solver);
  sim::SurfaceMesh whole;
  ASSERT_TRUE(solver->ExtractSurface(sim::SurfaceParams{}, &whole).ok());
  const int64_t n = whole.VertexCount();
  ASSERT_GT(n, 300);
  Buffer buffer;
  buffer.Grow(301);  // not a multiple of 3: whole triangles only
  ASSERT_TRUE(solver->BuildSurface(sim::SurfaceParams{}, nullptr).ok());
  ASSERT_TRUE(solver->WriteSurface(buffer.Target(), nullptr).ok());
  // Clamped on the device: the first 300 vertices, nothing past the buffer, the draw counts 300.
  EXPECT_EQ(buffer.draw[0], 300u);
  EXPECT_TRUE(std::equal(buffer.positions.begin(), buffer.positions.begin() + 900, whole.positions.begin()));
  EXPECT_TRUE(std::isnan(buffer.positions[900]) && std::isnan(buffer.positions[902]));
  // Reported to the host without a copy or a wait; the renderer grows its buffer from the report.
  const sim::SurfaceWriteReport r = solver->LastSurfaceWrite();
  EXPECT_TRUE(r.Clamped());
  EXPECT_EQ(r.vertices, n);
  EXPECT_EQ(r.written, 300);
  EXPECT_EQ(r.capacity, 301);
  buffer.Grow(r.vertices + r.vertices / 4);
  // The next frame fits: the whole mesh, bit for bit the host copy's.
  sim::SurfaceStats stats;
  ASSERT_TRUE(solver->BuildSurface(sim::SurfaceParams{}, &stats).ok());
  EXPECT_TRUE(stats.clamped) << "the build reports the last write: the clamped one";
  ASSERT_TRUE(solver->WriteSurface(buffer.Target(), &stats).ok());
  EXPECT_FALSE(stats.clamped);
  EXPECT_FALSE(solver->LastSurfaceWrite().Clamped());
  EXPECT_EQ(buffer.draw[0], static_cast<uint32_t>(n));
  EXPECT_TRUE(std::equal(whole.positions.begin(), whole.positions.end(), buffer.positions.begin()));
  EXPECT_TRUE(std::equal(whole.normals.begin(), whole.normals.end(), buffer.normals.begin()));
}

}  // namespace
}  // namespace sphxr::test
