#pragma once
// How the CPU backend's OpenMP threads wait and how many of them a step takes (docs/design/contention.md),
// and how many this process may start.
#include "sphxr/common/status.h"

namespace sphxr::sim {

/// The most CPU threads a solver takes: four per core of this machine, at least 64 (SolverConfig::threads;
/// the command line's --threads, sphxr.Run's threads and the sweeps' --workers are bounded by it).
int MaxSolverThreads();

/// Whether this process can start `threads` - 1 more threads now (0: one per core): they are started and joined before
/// the OpenMP runtime tries, whose failure (a process limit, `ulimit -u`) is its own line and exit.
/// The message names `what` (e.g. "--threads 60").
Status CheckThreadsCanStart(int threads, const std::string& what);

/// What the OpenMP runtime of this process was told about waiting, for the summary: "OMP_WAIT_POLICY=passive,
/// set by the user", or "the runtime's default" (libgomp: a spin of 300,000 rounds before sleeping).
const char* OpenMpWaitSetting();

}  // namespace sphxr::sim
