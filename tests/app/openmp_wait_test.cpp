// The program's bounded OpenMP spin (sim/openmp_wait.h, docs/design/contention.md): sphxr re-executes
// itself with GOMP_SPINCOUNT where the user set no wait setting, and keeps the user's where one is set.
// Read from the summary's device line, which says what the runtime of the running process was told.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "sphxr/sim/openmp_wait.h"

namespace {

std::string DeviceLine(const std::string& env) {
  const std::string command = "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT -u KMP_BLOCKTIME " + env + " '" SPHXR_BINARY
                              "' --headless --scene '" SPHXR_SCENES_DIR "/stir.json' --spacing 0.03 --steps 1"
                              " --no-progress 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return "popen failed";
  std::string out;
  char buf[4096];
  while (fgets(buf, sizeof buf, pipe) != nullptr) {
    const std::string line = buf;
    if (line.find("  device ") != std::string::npos) out += line;
  }
  pclose(pipe);
  return out;
}

TEST(OpenMpWait, TheProgramStartsWithItsBoundedSpin) {
  const std::string line = DeviceLine("");
  EXPECT_NE(line.find("GOMP_SPINCOUNT=" + std::to_string(sphxr::sim::kOpenMpSpinRounds) + ", sphxr's default)"),
            std::string::npos)
      << line;
}

TEST(OpenMpWait, TheUsersSettingIsKept) {
  EXPECT_NE(DeviceLine("OMP_WAIT_POLICY=passive").find("OMP_WAIT_POLICY=passive, set by the user)"), std::string::npos);
  EXPECT_NE(DeviceLine("GOMP_SPINCOUNT=123").find("GOMP_SPINCOUNT=123, set by the user)"), std::string::npos);
}

}  // namespace
