#pragma once
// The one place xr/ includes the OpenXR headers, with the platform bindings this build supports.
#if defined(_WIN32)
#define XR_USE_PLATFORM_WIN32
#include <windows.h>
#else
#define XR_USE_PLATFORM_XLIB
#include <GL/glx.h>
#include <X11/Xlib.h>
#endif
#define XR_USE_GRAPHICS_API_OPENGL
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#if !defined(_WIN32)
// Xlib defines Status, Bool and friends as macros; sphxr::Status must stay a type.
#undef Status
#undef Bool
#undef Success
#endif

#include <string>

#include "sphxr/common/status.h"

namespace sphxr::xr {

/// "XR_ERROR_SESSION_LOST" for a result, without an instance (xrResultToString needs one).
const char* ResultName(XrResult result);
/// "<call> failed: <RESULT> (<file>:<line>)".
Status XrFailure(const char* call, XrResult result, const char* file, int line);

}  // namespace sphxr::xr

/// Returns a Status naming the call, the result and the place when an OpenXR call fails.
#define SPHXR_XR_CHECK(call)                                                     \
  do {                                                                           \
    XrResult sphxrXrResult_ = (call);                                            \
    if (XR_FAILED(sphxrXrResult_))                                               \
      return ::sphxr::xr::XrFailure(#call, sphxrXrResult_, __FILE__, __LINE__);  \
  } while (0)
/// The same for a result already in hand: SPHXR_XR_CHECK_RESULT(xrCreateInstance, r).
#define SPHXR_XR_CHECK_RESULT(name, result)                                      \
  do {                                                                           \
    if (XR_FAILED(result))                                                       \
      return ::sphxr::xr::XrFailure(#name, result, __FILE__, __LINE__);          \
  } while (0)
