// CPU and CUDA backends run the same stages (sim/src/stages.h) from one source: the same small scene
// stepped 100 times on both must agree particle by particle. Skipped without a CUDA device.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "backend.h"
#include "support.h"

namespace sphxr::sim {
namespace {

HostFluid RunOn(Device device, const SceneSetup& scene, int steps, std::vector<float>* dts) {
  SolverConfig config = test::TestConfig();
  config.device = device;
  HostFluid out;
  auto solver = test::CreateOrFail(scene, config);
  if (!solver) return out;
  EXPECT_EQ(solver->ActiveDevice(), device);
  for (int s = 0; s < steps; ++s) {
    const Status st = solver->Step();
    if (!st.ok()) {
      ADD_FAILURE() << DeviceName(device) << " step " << s + 1 << ": " << st.message();
      return out;
    }
    dts->push_back(solver->LastStep().dt);
  }
  solver->Download(&out);
  return out;
}

TEST(CudaAgreementTest, CpuAndCudaAgreeAfter100Steps) {
  if (CudaDeviceCount() == 0) {
    GTEST_SKIP() << "no CUDA device: " << (CudaBackendCompiled() ? "the CUDA backend is built but no GPU answers"
                                                                 : "this build has no CUDA backend");
  }
  const SceneSetup scene = test::SmallDamBreak(0.01f);  // 900 particles
  std::vector<float> dtCpu, dtCuda;
  const HostFluid cpu = RunOn(Device::kCpu, scene, 100, &dtCpu);
  const HostFluid cuda = RunOn(Device::kCuda, scene, 100, &dtCuda);
  ASSERT_EQ(cpu.size(), 900u);
  ASSERT_EQ(cuda.size(), cpu.size());
  ASSERT_EQ(test::FirstNonFinite(cuda), "");
  for (size_t s = 0; s < dtCpu.size() && s < dtCuda.size(); ++s) {
    EXPECT_NEAR(dtCuda[s], dtCpu[s], 1e-4 * dtCpu[s]) << "time step " << s + 1;
  }
  const float tolerance = 1e-4f * scene.params.spacing;
  const auto byId = test::IndexById(cuda);
  float worst = 0.0f;
  int bad = 0;
  for (size_t i = 0; i < cpu.size(); ++i) {
    const auto it = byId.find(cpu.id[i]);
    ASSERT_NE(it, byId.end()) << "id " << cpu.id[i] << " missing on CUDA";
    const Vec4 a = cpu.position[i], b = cuda.position[it->second];
    const float d = std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
    worst = std::max(worst, d);
    if (d > tolerance && bad++ < 5) {
      ADD_FAILURE() << "id " << cpu.id[i] << ": cpu [" << a.x << ", " << a.y << ", " << a.z << "] cuda [" << b.x << ", "
                    << b.y << ", " << b.z << "], |d| = " << d / scene.params.spacing << " spacings";
    }
  }
  EXPECT_EQ(bad, 0) << "worst difference " << worst / scene.params.spacing << " spacings";
  RecordProperty("worst_difference_in_spacings", std::to_string(worst / scene.params.spacing));
  std::printf("[agreement] small dam break, 100 steps, cuda vs cpu: worst position difference %.3g spacings (bound 1e-4)\n",
              worst / scene.params.spacing);
}

TEST(CudaAgreementTest, SurfaceFieldAndMeshAgree) {
  if (CudaDeviceCount() == 0) GTEST_SKIP() << "no CUDA device";
  // The same particles (the scene's initial lattice) on both backends: the same lattice, the field
  // within 1e-5 (the sums run in the same order; only contraction may differ), meshes of nearly the
  // same size (a sample within rounding of the iso level can flip a case), and the CUDA mesh on the device.
  const SceneSetup scene = test::SmallDamBreak(0.01f);
  SolverConfig cudaConfig = test::TestConfig();
  cudaConfig.device = Device::kCuda;
  auto cpu = test::CreateOrFail(scene);
  auto cuda = test::CreateOrFail(scene, cudaConfig);
  ASSERT_TRUE(cpu && cuda);
  SurfaceParams params;
  params.cellSize = 0.0093f;
  SurfaceMeshView cpuView, cudaView;
  SurfaceStats cpuStats, cudaStats;
  ASSERT_TRUE(cpu->ExtractSurface(params, &cpuView, &cpuStats).ok());
  ASSERT_TRUE(cuda->ExtractSurface(params, &cudaView, &cudaStats).ok());
  EXPECT_FALSE(cpuView.onDevice);
  EXPECT_TRUE(cudaView.onDevice);
  EXPECT_EQ(cpuStats.grid.nx, cudaStats.grid.nx);
  EXPECT_EQ(cpuStats.grid.ny, cudaStats.grid.ny);
  EXPECT_EQ(cpuStats.grid.nz, cudaStats.grid.nz);
  EXPECT_NEAR(static_cast<double>(cudaStats.vertices), static_cast<double>(cpuStats.vertices), 0.01 * cpuStats.vertices);
  SurfaceMesh host;
  ASSERT_TRUE(cuda->ExtractSurface(params, &host).ok());
  EXPECT_EQ(host.VertexCount(), cudaStats.vertices);
  SurfaceGrid gridCpu, gridCuda;
  std::vector<float> fieldCpu, fieldCuda;
  cpu->BackendForTests()->Surface()->DownloadField(&gridCpu, &fieldCpu);
  cuda->BackendForTests()->Surface()->DownloadField(&gridCuda, &fieldCuda);
  // The CPU backend's lattice is the particles' bounding box within CUDA's clamp box, on the same
  // lattice lines: each CPU sample against CUDA's at the same point, every other CUDA sample 0.
  const test::SurfaceFieldDiff d = test::CompareSurfaceFields(gridCuda, fieldCuda, gridCpu, fieldCpu);
  ASSERT_TRUE(d.nested);
  EXPECT_LT(d.worst, 1e-5f);
  EXPECT_EQ(d.outside, 0.0f);  // beyond the margin of every particle: no kernel reaches
}

}  // namespace
}  // namespace sphxr::sim
