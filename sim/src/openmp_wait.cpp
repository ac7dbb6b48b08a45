// What the OpenMP runtime of this process was told about waiting (openmp_wait.h).
#include "sphxr/sim/openmp_wait.h"

#include <cstdlib>
#include <string>

namespace sphxr::sim {

const char* OpenMpWaitSetting() {
  static const std::string setting = [] {
    for (const char* name : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "KMP_BLOCKTIME"}) {
      const char* v = std::getenv(name);
      if (v != nullptr && *v != '\0') return std::string(name) + "=" + v + ", set by the user";
    }
    return std::string("the runtime's default");
  }();
  return setting.c_str();
}

}  // namespace sphxr::sim
