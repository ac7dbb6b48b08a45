// GuardBackend (sim/src/backend_guard.h): what thrust throws on a failed CUDA call or allocation
// becomes one line of Status naming the backend and the stage, never an exception across the module.
#include <gtest/gtest.h>

#include <new>
#include <stdexcept>
#include <string>

#include "backend_guard.h"
#include "support.h"

namespace sphxr::sim {
namespace {

TEST(GuardBackend, PassesTheWorksStatusThrough) {
  EXPECT_TRUE(GuardBackend("cuda", "the step", [] { return Status::Ok(); }).ok());
  const Status s = GuardBackend("cuda", "the step", [] { return Status::Error("own error"); });
  EXPECT_EQ(s.message(), "own error");
}

TEST(GuardBackend, AnAllocationFailureIsOneLineNamingTheStage) {
  const char* last = "grid";
  const Status s = GuardBackend("cuda", "the step", []() -> Status { throw std::bad_alloc(); }, &last);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cuda backend: out of memory in the step (after the grid stage)"), std::string::npos)
      << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
}

TEST(GuardBackend, ASystemErrorIsOneLineWithItsText) {
  // thrust::system_error is a std::runtime_error; its what() carries the CUDA error's text.
  const char* last = nullptr;
  const Status s = GuardBackend(
      "cuda", "the step", []() -> Status { throw std::runtime_error("parallel_for failed: cudaErrorIllegalAddress"); },
      &last);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), "cuda backend: the step (in its first stage) failed: parallel_for failed: cudaErrorIllegalAddress");
}

// A bug, not an error of the environment: an index past the bodies stops a debug build with the
// condition and place (SPHXR_ASSERT); a release build compiles the check out.
TEST(SphxrAssert, ABodyIndexPastTheBodiesStopsADebugBuild) {
#ifdef NDEBUG
  GTEST_SKIP() << "a release build: SPHXR_ASSERT is compiled out";
#else
  ::testing::GTEST_FLAG(death_test_style) = "threadsafe";
  auto solver = test::CreateOrFail(test::SmallDamBreak(0.02f));
  ASSERT_TRUE(solver);
  EXPECT_DEATH((void)solver->BodyPose(0), "SPHXR_ASSERT\\(body >= 0 && body < BodyCount\\(\\)\\) failed");
#endif
}

}  // namespace
}  // namespace sphxr::sim
