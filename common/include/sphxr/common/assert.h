#pragma once
// SPHXR_ASSERT: a bug check (STYLE.md: errors of the environment return a Status, bugs are asserts), at
// API entries and where an index is trusted (Box2D's B2_ASSERT habit). In CUDA device code it is the
// device `assert` (the kernel traps and the next CudaTraits::Sync reports it, naming the stage); on the
// host it is checked in debug builds and prints the condition and place before aborting. Release builds
// (NDEBUG) compile it out on both, so it costs the hot loops nothing.
#include <cassert>
#include <cstdio>
#include <cstdlib>

namespace sphxr {

[[noreturn]] inline void AssertFailed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "%s:%d: SPHXR_ASSERT(%s) failed\n", file, line, condition);
  std::abort();
}

}  // namespace sphxr

#if defined(NDEBUG)
#define SPHXR_ASSERT(condition) ((void)0)
#elif defined(__CUDA_ARCH__)
#define SPHXR_ASSERT(condition) assert(condition)
#else
#define SPHXR_ASSERT(condition) ((condition) ? (void)0 : ::sphxr::AssertFailed(#condition, __FILE__, __LINE__))
#endif
