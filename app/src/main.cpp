// sphxr: the command line. Desktop and XR modes arrive with the renderer and the XR layer; until then
// every run is headless.
#include <cstdio>

#include "sphxr/app/headless.h"
#include "sphxr/common/log.h"

int main(int argc, char** argv) {
  sphxr::app::Options options;
  if (sphxr::Status s = sphxr::app::ParseCommandLine(argc, argv, &options); !s) {
    std::fprintf(stderr, "sphxr: %s\n", s.message().c_str());
    return 2;
  }
  if (options.help) {
    std::fputs(sphxr::app::UsageText().c_str(), stdout);
    return 0;
  }
  if (options.mode == sphxr::app::Mode::kDesktop || options.mode == sphxr::app::Mode::kXr) {
    std::fprintf(stderr, "sphxr: %s mode is not part of this build yet (the renderer and XR layer are open issues); "
                         "use --headless\n", options.mode == sphxr::app::Mode::kXr ? "--xr" : "--desktop");
    return 2;
  }
  if (options.mode == sphxr::app::Mode::kAuto) {
    SPHXR_LOG_INFO("no window or headset modes in this build yet: running headless");
  }
  sphxr::app::RunSummary summary;
  if (sphxr::Status s = sphxr::app::RunHeadless(options, &summary); !s) {
    std::fprintf(stderr, "sphxr: error: %s\n", s.message().c_str());
    return 1;
  }
  return 0;
}
