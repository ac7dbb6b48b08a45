#pragma once
// Whether a window can be opened at all: the desktop window needs a display, and so does the headset
// (its mirror window owns the GL context). main.cpp picks the mode from it.

namespace sphxr::app {

/// True when a display server is advertised (DISPLAY or WAYLAND_DISPLAY).
bool DisplayAvailable();

}  // namespace sphxr::app
