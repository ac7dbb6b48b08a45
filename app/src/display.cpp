#include "sphxr/app/display.h"

#include <cstdlib>

namespace sphxr::app {

bool DisplayAvailable() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

}  // namespace sphxr::app
