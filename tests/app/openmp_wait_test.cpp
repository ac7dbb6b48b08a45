// The summary says how the CPU backend's OpenMP threads wait (sim/openmp_wait.h, docs/design/contention.md):
// the runtime's default, or the user's setting (shown through ShowText: a value is the user's text).
// Read from the summary's device line, which says what the runtime of the running process was told.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>


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

TEST(OpenMpWait, TheSummarySaysTheRuntimesDefault) {
  const std::string line = DeviceLine("");
  EXPECT_NE(line.find("cpu (OpenMP wait: the runtime's default)"), std::string::npos) << line;
}

TEST(OpenMpWait, TheSummarySaysTheUsersSetting) {
  EXPECT_NE(DeviceLine("OMP_WAIT_POLICY=passive").find("OMP_WAIT_POLICY=passive, set by the user)"), std::string::npos);
  EXPECT_NE(DeviceLine("GOMP_SPINCOUNT=123").find("GOMP_SPINCOUNT=123, set by the user)"), std::string::npos);
  // an escape in the value is shown, not sent to the terminal (libgomp itself ignores the bad value)
  const std::string escaped = DeviceLine("'OMP_WAIT_POLICY=passive\033[2J'");
  EXPECT_EQ(escaped.find('\033'), std::string::npos) << escaped;
  EXPECT_NE(escaped.find("OMP_WAIT_POLICY=passive"), std::string::npos) << escaped;
}

}  // namespace
