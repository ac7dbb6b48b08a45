// libFuzzer target: a trajectory CSV (interaction/src/trajectory.cpp). Any input must give a
// trajectory or a one-line error; a trajectory given must sample to finite poses.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sphxr/common/log.h"
#include "sphxr/interaction/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool quiet = [] {
    sphxr::SetLogLevel(sphxr::LogLevel::kError);
    return true;
  }();
  (void)quiet;
  sphxr::interaction::Trajectory t;
  const sphxr::Status s =
      sphxr::interaction::Trajectory::Parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.csv", &t);
  if (!s) {
    if (s.message().find('\n') != std::string::npos || s.message().size() > 400) std::abort();
    return 0;
  }
  for (const double time : {t.StartTime(), 0.5 * (t.StartTime() + t.EndTime()), t.EndTime() + 1.0}) {
    const sphxr::interaction::HandInput hand = t.Sample(time);
    const auto& p = hand.pose.position;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
  }
  return 0;
}
