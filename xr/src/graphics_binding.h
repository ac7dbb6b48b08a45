#pragma once
#include "openxr_include.h"
#include "sphxr/xr/session.h"

namespace sphxr::xr {

/// Storage for the platform's XrGraphicsBindingOpenGL*KHR; `header` points at the filled one.
struct PlatformBinding {
#if defined(_WIN32)
  XrGraphicsBindingOpenGLWin32KHR win32{};
#else
  XrGraphicsBindingOpenGLXlibKHR xlib{};
#endif
  const XrBaseInStructure* header = nullptr;
};
Status MakePlatformBinding(const GraphicsBinding& in, PlatformBinding* out);

}  // namespace sphxr::xr
