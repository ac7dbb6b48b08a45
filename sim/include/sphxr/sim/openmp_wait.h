#pragma once
// How the CPU backend's OpenMP threads wait at the end of a parallel region (docs/design/contention.md).
//
// libgomp's default lets an idle thread spin for 300,000 rounds (milliseconds) before it sleeps. Alone on
// the machine that is the fastest choice; beside one other busy process it is the slowest: the thread that
// spins holds a core the descheduled thread of the same team needs, and a 2-thread step of `stir` took 31x
// its time alone. A short spin keeps the speed alone (the next region starts within microseconds) and
// gives the core away under contention.
#include <cstdint>

namespace sphxr::sim {

/// The spin, in libgomp's rounds (GOMP_SPINCOUNT), that sphxr's programs start with (measured:
/// bench/contention.sh, bench/results/contention.csv).
inline constexpr int64_t kOpenMpSpinRounds = 10000;

/// Call first in main(). Where the user set neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT (nor KMP_BLOCKTIME
/// for LLVM's runtime), sets the bounded spin. libgomp reads its settings once, when it is loaded, before
/// main runs, so with libgomp this re-executes the program (/proc/self/exe, the same arguments and pid)
/// with the setting in its environment; LLVM's libomp reads them at the first parallel region, so the
/// setting alone is enough. Returns (changing nothing) where the settings are the user's, or where the
/// re-execution fails (the run then keeps libgomp's default, and says so at debug level).
void BoundOpenMpSpin(char** argv);

/// What the OpenMP runtime of this process was told, for the summary and the log: "GOMP_SPINCOUNT=10000,
/// sphxr's default", "OMP_WAIT_POLICY=passive, set by the user", ...
const char* OpenMpWaitSetting();

}  // namespace sphxr::sim
