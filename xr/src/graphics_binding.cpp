// The platform half of XR_KHR_opengl_enable: the binding structure chained into xrCreateSession.
// Linux uses Xlib/GLX; the Win32 binding slots in beside it (compiled on Windows only).
#include "graphics_binding.h"

namespace sphxr::xr {

#if defined(_WIN32)

Status CurrentXlibGlxBinding(void*, GraphicsBinding*) {
  return Status::Error("the Xlib/GLX OpenXR binding is not available on Windows (fill GraphicsBinding::win32)");
}

Status MakePlatformBinding(const GraphicsBinding& in, PlatformBinding* out) {
  if (!in.win32.hDC || !in.win32.hGLRC) return Status::Error("OpenXR: GraphicsBinding::win32 is not filled in");
  out->win32 = {XR_TYPE_GRAPHICS_BINDING_OPENGL_WIN32_KHR, nullptr, static_cast<HDC>(in.win32.hDC),
                static_cast<HGLRC>(in.win32.hGLRC)};
  out->header = reinterpret_cast<const XrBaseInStructure*>(&out->win32);
  return Status::Ok();
}

#else

Status CurrentXlibGlxBinding(void* display, GraphicsBinding* binding) {
  GLXContext context = glXGetCurrentContext();
  if (!display || !context) return Status::Error("OpenXR needs a current GLX context on an X display");
  binding->xlib.display = display;
  binding->xlib.context = context;
  binding->xlib.drawable = glXGetCurrentDrawable();
  return Status::Ok();
}

Status MakePlatformBinding(const GraphicsBinding& in, PlatformBinding* out) {
  if (!in.xlib.display || !in.xlib.context || !in.xlib.drawable)
    return Status::Error("OpenXR: GraphicsBinding::xlib is not filled in (see CurrentXlibGlxBinding)");
  auto* display = static_cast<Display*>(in.xlib.display);
  auto context = static_cast<GLXContext>(in.xlib.context);
  // The spec wants the context's framebuffer config and visual: ask GLX which ones it was made with.
  int fbConfigId = 0, screen = 0;
  glXQueryContext(display, context, GLX_FBCONFIG_ID, &fbConfigId);
  glXQueryContext(display, context, GLX_SCREEN, &screen);
  int attribs[] = {GLX_FBCONFIG_ID, fbConfigId, None};
  int count = 0;
  GLXFBConfig* configs = glXChooseFBConfig(display, screen, attribs, &count);
  GLXFBConfig config = (configs && count > 0) ? configs[0] : nullptr;
  uint32_t visualId = 0;
  if (config) {
    if (XVisualInfo* vi = glXGetVisualFromFBConfig(display, config)) {
      visualId = uint32_t(vi->visualid);
      XFree(vi);
    }
  }
  if (configs) XFree(configs);
  out->xlib = {XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR, nullptr, display, visualId, config,
               static_cast<GLXDrawable>(in.xlib.drawable), context};
  out->header = reinterpret_cast<const XrBaseInStructure*>(&out->xlib);
  return Status::Ok();
}

#endif

}  // namespace sphxr::xr
