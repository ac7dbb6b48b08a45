// A headless run that sphxr chose itself (no display) says in one line which window options it cannot
// honour (an explicit --headless refuses them: cli_test.cpp).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace {

std::string Stderr(const std::string& args) {
  const std::string command = "env -u DISPLAY -u WAYLAND_DISPLAY -u XR_RUNTIME_JSON '" SPHXR_BINARY "' --scene '" SPHXR_SCENES_DIR
                              "/stir.json' --spacing 0.03 --steps 1 --no-progress " + args + " 2>&1 >/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return "popen failed";
  std::string out;
  char buf[4096];
  while (fgets(buf, sizeof buf, pipe) != nullptr) out += buf;
  pclose(pipe);
  return out;
}

TEST(FallbackOptions, AChosenHeadlessRunNamesTheWindowOptionsItCannotHonour) {
  const std::string err = Stderr("--window-size 640x480 --frame-limit 5");
  EXPECT_NE(err.find("running headless: no window, so --window-size --frame-limit have no effect"), std::string::npos)
      << err;
  EXPECT_EQ(Stderr("").find("no effect"), std::string::npos);
}

}  // namespace
