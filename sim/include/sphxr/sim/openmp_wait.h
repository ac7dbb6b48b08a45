#pragma once
// How the CPU backend's OpenMP threads wait and how many of them a step takes (docs/design/contention.md).

namespace sphxr::sim {

/// What the OpenMP runtime of this process was told about waiting, for the summary: "OMP_WAIT_POLICY=passive,
/// set by the user", or "the runtime's default" (libgomp: a spin of 300,000 rounds before sleeping).
const char* OpenMpWaitSetting();

}  // namespace sphxr::sim
