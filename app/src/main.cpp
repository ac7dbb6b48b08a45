// sphxr: the command line. Picks the mode: --desktop (the default when a display is present), else
// --headless; a window that cannot open falls back to headless with one line saying why.
#include <cstdio>

#include "sphxr/app/desktop.h"
#include "sphxr/app/headless.h"
#include "sphxr/common/log.h"

int main(int argc, char** argv) {
  using sphxr::app::Mode;
  sphxr::app::Options options;
  if (sphxr::Status s = sphxr::app::ParseCommandLine(argc, argv, &options); !s) {
    std::fprintf(stderr, "sphxr: %s\n", s.message().c_str());
    return 2;
  }
  if (options.help) {
    std::fputs(sphxr::app::UsageText().c_str(), stdout);
    return 0;
  }
  if (options.mode == Mode::kXr) {
    SPHXR_LOG_WARN("--xr: the XR layer is not part of this build yet: using the desktop window");
    options.mode = Mode::kDesktop;
  }
  bool autoPicture = false;  // a picture nobody asked for must not cost the run when EGL is missing
  if (options.mode == Mode::kAuto) {
    options.mode = sphxr::app::DisplayAvailable() ? Mode::kDesktop : Mode::kHeadless;
    if (options.mode == Mode::kHeadless) {
      SPHXR_LOG_INFO("no display (DISPLAY is not set): running headless; a picture goes to %s",
                     options.screenshotPath.empty() ? "sphxr_screenshot.png" : options.screenshotPath.c_str());
      if (options.screenshotPath.empty()) {
        options.screenshotPath = "sphxr_screenshot.png";
        autoPicture = true;
      }
    }
  }
  if (options.mode == Mode::kDesktop) {
    const sphxr::Status s = sphxr::app::RunDesktop(options);
    if (s) return 0;
    SPHXR_LOG_WARN("desktop window unavailable (%s): running headless", s.message().c_str());
    options.mode = Mode::kHeadless;
  }
  sphxr::app::RunSummary summary;
  sphxr::Status run = sphxr::app::RunHeadless(options, &summary);
  if (!run && autoPicture && run.message().rfind("--screenshot/--frames:", 0) == 0) {
    SPHXR_LOG_WARN("no picture (%s): running without one", run.message().c_str());
    options.screenshotPath.clear();
    run = sphxr::app::RunHeadless(options, &summary);
  }
  if (sphxr::Status s = run; !s) {
    std::fprintf(stderr, "sphxr: error: %s\n", s.message().c_str());
    return 1;
  }
  return 0;
}
