// libFuzzer target: a state file's bytes (app/src/state_file.cpp ParseStateFile). Any input must be
// read or refused in one line, with no crash, huge allocation or sanitizer report.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool quiet = [] {
    sphxr::SetLogLevel(sphxr::LogLevel::kError);
    return true;
  }();
  (void)quiet;
  sphxr::app::StateFile state;
  const sphxr::Status s = sphxr::app::ParseStateFile(std::vector<char>(data, data + size), "fuzz.state", &state);
  if (!s && s.message().find('\n') != std::string::npos) std::abort();
  return 0;
}
