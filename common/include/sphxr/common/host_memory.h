#pragma once
// How much memory this process may use, for refusing a scene that would not fit with a message instead
// of the OOM killer.
#include <cstdint>

namespace sphxr {

/// Three quarters of the physical memory, lowered to half of an address-space limit (ulimit -v) and to
/// three quarters of a memory cgroup's limit (v2, also the process's own cgroup, or v1) where there is
/// one. INT64_MAX when nothing can be read.
int64_t AvailableHostBytes();

}  // namespace sphxr
