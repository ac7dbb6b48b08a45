// The device names of the command line and the scene's solver, and what each one creates.
#include <gtest/gtest.h>

#include <string>

#include "backend.h"
#include "support.h"

namespace sphxr::sim {
namespace {

TEST(Device, EveryNameParsesToTheDeviceItNames) {
  for (Device d : {Device::kAuto, Device::kCpu, Device::kCuda, Device::kCpuReference}) {
    Device parsed = Device::kAuto;
    ASSERT_TRUE(ParseDevice(DeviceName(d), &parsed)) << DeviceName(d);
    EXPECT_EQ(parsed, d);
  }
  EXPECT_STREQ(DeviceName(Device::kCpuReference), "cpu-reference");
  Device untouched = Device::kCpu;
  for (const char* bad : {"gpu", "cpu_reference", "reference", "CPU", ""}) EXPECT_FALSE(ParseDevice(bad, &untouched)) << bad;
  EXPECT_EQ(untouched, Device::kCpu);
}

TEST(Device, CpuReferenceCreatesTheHostReferenceOfTheCudaBackend) {
  SolverConfig config = test::TestConfig();
  config.device = Device::kCpuReference;
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.02f), config);
  ASSERT_TRUE(solver);
  EXPECT_EQ(solver->ActiveDevice(), Device::kCpuReference);
  EXPECT_STREQ(solver->BackendForTests()->Name(), "cpu-reference");
  // Its mesh is host memory (the CUDA backend's is device memory).
  SurfaceMeshView view;
  ASSERT_TRUE(solver->ExtractSurface(SurfaceParams{}, &view).ok());
  EXPECT_FALSE(view.onDevice);
}

}  // namespace
}  // namespace sphxr::sim
