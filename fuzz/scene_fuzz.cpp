// libFuzzer target: a scene file's text (app/src/scene_file.cpp). Any input must give a scene or a
// one-line error, with no crash, hang or sanitizer report. Trajectory files named by a scene are read
// from the working directory (scripts/fuzz.sh runs in an empty one).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool quiet = [] {
    sphxr::SetLogLevel(sphxr::LogLevel::kError);  // unknown keys are warned about: thousands a second
    return true;
  }();
  (void)quiet;
  sphxr::app::SceneFile scene;
  const sphxr::Status s = sphxr::app::ParseScene(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", &scene);
  // One short line, with nothing a terminal would act on (fuzz/scene.dict brings control and bidi
  // characters); a scene's and its paddles' names are plain text too.
  if (!s && (!sphxr::IsPlainText(s.message()) || s.message().size() > 400)) std::abort();
  if (s && !sphxr::IsPlainText(scene.name)) std::abort();
  for (const std::string& w : scene.warnings) {
    if (!sphxr::IsPlainText(w)) std::abort();
  }
  return 0;
}
