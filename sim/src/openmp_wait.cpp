// The bounded spin of the CPU backend's OpenMP threads (openmp_wait.h, docs/design/contention.md).
#include "sphxr/sim/openmp_wait.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "sphxr/common/log.h"

namespace sphxr::sim {
namespace {

constexpr const char* kMarker = "SPHXR_OPENMP_SPIN_SET";  // set across the re-execution only
std::string g_setting = "the OpenMP runtime's default";

const char* Env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? v : nullptr;
}

}  // namespace

void BoundOpenMpSpin(char** argv) {
  if (Env(kMarker) != nullptr) {  // the re-executed program: the setting is sphxr's
    unsetenv(kMarker);
    g_setting = std::string("GOMP_SPINCOUNT=") + (Env("GOMP_SPINCOUNT") ? Env("GOMP_SPINCOUNT") : "?") + ", sphxr's default";
    return;
  }
  for (const char* name : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "KMP_BLOCKTIME"}) {
    if (const char* v = Env(name)) {
      g_setting = std::string(name) + "=" + v + ", set by the user";
      return;
    }
  }
  const std::string rounds = std::to_string(kOpenMpSpinRounds);
  // LLVM's runtime (the sanitizer builds) reads KMP_BLOCKTIME at its first parallel region; its unit is
  // the millisecond, far coarser than the spin wanted, so its threads sleep at once (speed does not matter
  // in those builds; the behaviour under a busy neighbour does).
  if (dlsym(RTLD_DEFAULT, "kmp_set_blocktime") != nullptr) {
    setenv("KMP_BLOCKTIME", "0", 1);
    g_setting = "KMP_BLOCKTIME=0, sphxr's default";
    return;
  }
  if (argv == nullptr || argv[0] == nullptr) return;
  setenv("GOMP_SPINCOUNT", rounds.c_str(), 1);
  setenv(kMarker, "1", 1);
  std::fflush(nullptr);
  execv("/proc/self/exe", argv);
  // Not re-executed (no /proc, a sandbox): libgomp keeps its default spin.
  unsetenv("GOMP_SPINCOUNT");
  unsetenv(kMarker);
  g_setting = "libgomp's default spin (re-executing with GOMP_SPINCOUNT failed)";
}

const char* OpenMpWaitSetting() { return g_setting.c_str(); }

}  // namespace sphxr::sim
