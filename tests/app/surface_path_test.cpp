// How the water surface reaches GL (docs/dev/rendering.md, "The surface's two paths"): copied to the host
// on the CPU backend, written in place through CUDA-GL interop when the solver runs on the CUDA device.
// No GPU here: the choice and the CPU side are tested; the interop write itself has never run.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "interop_surface.h"  // app/src: InteropSurface
#include "sim_worker.h"        // app/src: SimWorker
#include "sphxr/app/scene_file.h"
#include "sphxr/app/snapshot.h"
#include "support.h"

namespace sphxr::app {
namespace {

using test::kSmallTankScene;  // tests/support.h: 720 particles, some hundreds of triangles

TEST(SurfacePathTest, InteropOnlyForASolverOnTheCudaDevice) {
  EXPECT_EQ(ChooseSurfacePath(sim::Device::kCuda), SurfacePath::kInterop);
  EXPECT_EQ(ChooseSurfacePath(sim::Device::kCpu), SurfacePath::kHostCopy);
  EXPECT_EQ(ChooseSurfacePath(sim::Device::kAuto), SurfacePath::kHostCopy);  // never an active device
  EXPECT_STREQ(SurfacePathName(SurfacePath::kInterop), "CUDA-GL interop");
  EXPECT_STREQ(SurfacePathName(SurfacePath::kHostCopy), "host copy");
}

TEST(SurfacePathTest, WorkerOnTheCpuPublishesTheHostMeshAndSaysSoOnce) {
  SceneFile scene;
  ASSERT_TRUE(ParseScene(kSmallTankScene, "small", &scene).ok());
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
  config.threads = 1;
  test::LogCapture log;
  ResetLogOnce();
  SimWorker worker(config);
  ASSERT_TRUE(worker.Start(SimSceneFromFile(scene)).ok());
  EXPECT_EQ(worker.Path(), SurfacePath::kHostCopy);
  const std::shared_ptr<const SimSnapshot> snap = worker.Latest();
  ASSERT_TRUE(snap);
  EXPECT_TRUE(snap->surfaceFresh);
  EXPECT_FALSE(snap->surfaceOnDevice);
  EXPECT_EQ(snap->surfaceBuild, 0u);
  EXPECT_GT(snap->surface.TriangleCount(), 100);
  EXPECT_EQ(snap->SurfaceTriangles(), snap->surface.TriangleCount());
  // The GL side has nothing to write on this path: it draws the snapshot's host mesh.
  std::unique_ptr<render::InteropMesh> mesh;
  uint64_t build = 7;
  const Status s = worker.WriteSurfaceInto(&mesh, &build);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("copied to the host"), std::string::npos) << s.message();
  EXPECT_EQ(build, 0u);
  EXPECT_FALSE(mesh);
  InteropSurface interop;
  EXPECT_EQ(interop.Update(worker, *snap), nullptr);
  worker.Stop();
  EXPECT_EQ(log.Count("surface: solver on the CPU"), 1) << log.All();
  EXPECT_EQ(log.Count("CUDA-GL interop"), 0) << log.All();
}

TEST(SurfacePathTest, InteropCaptureBuildsTheMeshWithoutCopyingIt) {
  // The snapshot side of the GPU path, run on the CPU backend (BuildSurface is backend-independent):
  // the solver keeps the mesh, the snapshot carries only its size.
  SceneFile scene;
  ASSERT_TRUE(ParseScene(kSmallTankScene, "small", &scene).ok());
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
  config.threads = 1;
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(scene.setup, config, &solver).ok());
  SimSnapshot host, device;
  ASSERT_TRUE(CaptureSnapshot(*solver, nullptr, {}, &host).ok());
  ASSERT_TRUE(CaptureSnapshot(*solver, nullptr, {}, &device, SurfacePath::kInterop).ok());
  EXPECT_FALSE(host.surfaceOnDevice);
  EXPECT_TRUE(device.surfaceOnDevice);
  EXPECT_TRUE(device.surfaceFresh);
  EXPECT_EQ(device.surface.VertexCount(), 0);
  EXPECT_EQ(device.surfaceVertices, host.surface.VertexCount());
  EXPECT_EQ(device.SurfaceTriangles(), host.SurfaceTriangles());
  EXPECT_EQ(device.surfaceCellSize, host.surfaceCellSize);
  // The GL thread writes the build later, maybe after more steps (and a kept build again): the steps do
  // not change what WriteSurface writes.
  const int64_t n = device.surfaceVertices;
  std::vector<float> p0(3 * n), n0(3 * n), p1(3 * n), n1(3 * n);
  ASSERT_TRUE(solver->WriteSurface({p0.data(), n0.data(), n}, nullptr).ok());
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(solver->Step().ok());
  ASSERT_TRUE(solver->WriteSurface({p1.data(), n1.data(), n}, nullptr).ok());
  EXPECT_EQ(p0, host.surface.positions);
  EXPECT_EQ(n0, host.surface.normals);
  EXPECT_EQ(p1, p0);
  EXPECT_EQ(n1, n0);
  SurfaceRequest off;
  off.enabled = false;
  ASSERT_TRUE(CaptureSnapshot(*solver, nullptr, off, &device, SurfacePath::kInterop).ok());
  EXPECT_FALSE(device.surfaceOnDevice);
  EXPECT_EQ(device.SurfaceTriangles(), 0);
}

TEST(SurfacePathTest, InteropBuffersGrowFromTheLastWriteReport) {
  // The GL thread never reads the mesh's size before a write: it sizes the buffers from the solver's
  // last write report (a frame late on the CUDA device) and grows them after a clamped write.
  sim::SurfaceWriteReport none;
  EXPECT_EQ(InteropCapacity(0, none), 3 * 4096) << "the first buffers";
  sim::SurfaceWriteReport fits;
  fits.vertices = fits.written = 9000;
  fits.capacity = 3 * 4096;
  fits.write = 1;
  EXPECT_EQ(InteropCapacity(3 * 4096, fits), 3 * 4096);
  sim::SurfaceWriteReport clamped;
  clamped.vertices = 30000;
  clamped.written = clamped.capacity = 3 * 4096;
  clamped.write = 2;
  ASSERT_TRUE(clamped.Clamped());
  const int64_t grown = InteropCapacity(3 * 4096, clamped);
  EXPECT_GE(grown, 30000 + 30000 / 4 - 2);
  EXPECT_EQ(grown % 3, 0) << "whole triangles";
  EXPECT_EQ(InteropCapacity(grown, clamped), grown) << "grown once";
  clamped.vertices = int64_t{1} << 26;
  EXPECT_LE(InteropCapacity(grown, clamped), int64_t{1} << 26);
}

TEST(SurfacePathTest, AnInteropSnapshotInWaterModeCopiesNoParticles) {
  // Its reader draws the mesh written in place: the particles are not copied back. Particle mode, and
  // the host path, copy them all.
  SurfaceRequest water, particles;
  particles.enabled = false;
  EXPECT_EQ(ParticlesFor(SurfacePath::kInterop, water), ParticleCopy::kNone);
  EXPECT_EQ(ParticlesFor(SurfacePath::kInterop, particles), ParticleCopy::kAll);
  EXPECT_EQ(ParticlesFor(SurfacePath::kHostCopy, water), ParticleCopy::kAll);
  SceneFile scene;
  ASSERT_TRUE(ParseScene(kSmallTankScene, "small", &scene).ok());
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
  config.threads = 1;
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(scene.setup, config, &solver).ok());
  SimSnapshot snap;
  ASSERT_TRUE(CaptureSnapshot(*solver, nullptr, water, &snap, SurfacePath::kInterop, ParticleCopy::kNone).ok());
  EXPECT_EQ(snap.fluid.size(), 0u);
  EXPECT_EQ(snap.fluidCount, solver->FluidCount());
  EXPECT_TRUE(snap.surfaceOnDevice);
  ASSERT_TRUE(CaptureSnapshot(*solver, nullptr, particles, &snap, SurfacePath::kInterop).ok());
  EXPECT_EQ(static_cast<int>(snap.fluid.size()), solver->FluidCount());
}

}  // namespace
}  // namespace sphxr::app
