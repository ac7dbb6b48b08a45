#include "sphxr/common/host_memory.h"

#include <exception>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace sphxr {

int64_t AvailableHostBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long pageSize = sysconf(_SC_PAGE_SIZE);
  int64_t have = std::numeric_limits<int64_t>::max();
  if (pages > 0 && pageSize > 0) have = static_cast<int64_t>(pages) * pageSize * 3 / 4;  // a quarter to the OS and renderer
  // A process limit (ulimit -v) is a harder ceiling; half of it, as the program and its libraries
  // (OpenGL, OpenMP stacks) map a lot of address space of their own.
  struct rlimit limit;
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    have = std::min<int64_t>(have, static_cast<int64_t>(limit.rlim_cur / 2));
  }
  // In a container the memory cgroup's limit is the real one (past it the OOM killer ends the process,
  // instead of this friendly refusal): v2's memory.max ("max": none), v1's limit_in_bytes (a huge
  // number: none). Three quarters of it, as of the physical memory.
  // (v2: also the process's own cgroup, from /proc/self/cgroup's "0::/path": systemd and batch
  // schedulers set the limit there, not at the root.)
  std::vector<std::string> limits = {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"};
  {
    std::ifstream cgroup("/proc/self/cgroup");
    std::string line;
    while (std::getline(cgroup, line)) {
      if (line.rfind("0::/", 0) == 0 && line.size() > 4) limits.push_back("/sys/fs/cgroup" + line.substr(3) + "/memory.max");
    }
  }
  for (const std::string& path : limits) {
    std::ifstream in(path);
    long long bytes = 0;
    if (in >> bytes && bytes > 0) have = std::min<int64_t>(have, bytes / 4 * 3);
  }
  return have;
}

namespace {
thread_local const char* g_memoryUse = nullptr;
thread_local const char* g_unwound = nullptr;  // the innermost use an exception left through
}  // namespace

MemoryUse::MemoryUse(const char* what) : m_previous(g_memoryUse), m_exceptions(std::uncaught_exceptions()) {
  g_memoryUse = what;
}
MemoryUse::~MemoryUse() {
  if (std::uncaught_exceptions() > m_exceptions && !g_unwound) g_unwound = g_memoryUse;
  g_memoryUse = m_previous;
}
const char* CurrentMemoryUse() { return g_memoryUse ? g_memoryUse : g_unwound; }

}  // namespace sphxr
