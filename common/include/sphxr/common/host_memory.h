#pragma once
// How much memory this process may use, for refusing a scene that would not fit with a message instead
// of the OOM killer.
#include <cstdint>

namespace sphxr {

/// Three quarters of the physical memory, lowered to half of an address-space limit (ulimit -v) and to
/// three quarters of a memory cgroup's limit (v2, also the process's own cgroup, or v1) where there is
/// one. INT64_MAX when nothing can be read.
int64_t AvailableHostBytes();

/// What the process is allocating for, while one is alive (innermost wins): the out-of-memory message
/// names it ("out of memory: use a larger --spacing" blamed the spacing when the probe rows had grown).
class MemoryUse {
 public:
  explicit MemoryUse(const char* what);
  ~MemoryUse();
  MemoryUse(const MemoryUse&) = delete;
  MemoryUse& operator=(const MemoryUse&) = delete;

 private:
  const char* m_previous;
  int m_exceptions;
};
/// The innermost MemoryUse's text, or the innermost one an exception left through; null when none.
const char* CurrentMemoryUse();

}  // namespace sphxr
