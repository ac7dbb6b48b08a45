// tests/sim/cpu_stages_test.cpp built for the portable x86-64 tier (SSE2, no gather instruction): the
// tier a build with SPHXR_NATIVE=OFF runs. Its own executable, so the tier's inline namespace cannot
// meet the native tier's copies at link time.
#include "sim/cpu_stages_test.cpp"
