// The session's swapchains: the colour format (the runtime's first sRGB one) and depth format, one
// colour and one depth swapchain per eye (or a depth texture of our own), one framebuffer per eye;
// and the few GL entry points xr/ loads through the application's getProcAddress.
#include <vector>

#include "gl_functions.h"
#include "openxr_include.h"
#include "session_impl.h"
#include "sphxr/common/log.h"

namespace sphxr::xr {

bool GlFunctions::Load(void* (*get)(const char*), const char** missing) {
#define SPHXR_GL_LOAD(field, name)                                    \
  field = reinterpret_cast<decltype(field)>(get(name));               \
  if (!field) {                                                       \
    *missing = name;                                                  \
    return false;                                                     \
  }
  SPHXR_GL_LOAD(GenFramebuffers, "glGenFramebuffers")
  SPHXR_GL_LOAD(DeleteFramebuffers, "glDeleteFramebuffers")
  SPHXR_GL_LOAD(BindFramebuffer, "glBindFramebuffer")
  SPHXR_GL_LOAD(FramebufferTexture2D, "glFramebufferTexture2D")
  SPHXR_GL_LOAD(CheckFramebufferStatus, "glCheckFramebufferStatus")
  SPHXR_GL_LOAD(Viewport, "glViewport")
  SPHXR_GL_LOAD(GetIntegerv, "glGetIntegerv")
  SPHXR_GL_LOAD(GetString, "glGetString")
  SPHXR_GL_LOAD(GenTextures, "glGenTextures")
  SPHXR_GL_LOAD(DeleteTextures, "glDeleteTextures")
  SPHXR_GL_LOAD(BindTexture, "glBindTexture")
  SPHXR_GL_LOAD(TexImage2D, "glTexImage2D")
  SPHXR_GL_LOAD(Enable, "glEnable")
  SPHXR_GL_LOAD(Disable, "glDisable")
  SPHXR_GL_LOAD(IsEnabled, "glIsEnabled")
#undef SPHXR_GL_LOAD
  return true;
}

Status Session::Impl::CreateSwapchains() {
  uint32_t count = 0;
  SPHXR_XR_CHECK(xrEnumerateSwapchainFormats(session, 0, &count, nullptr));
  std::vector<int64_t> formats(count);
  SPHXR_XR_CHECK(xrEnumerateSwapchainFormats(session, count, &count, formats.data()));
  // The runtime lists formats in its order of preference: take its first sRGB colour format.
  for (int64_t f : formats)
    if (f == gl::kSrgb8Alpha8 || f == gl::kSrgb8) {
      colorFormat = f;
      break;
    }
  if (!colorFormat) {
    for (int64_t f : formats)
      if (f == gl::kRgba8) colorFormat = f;
    if (!colorFormat) return Status::Error("OpenXR: the runtime offers neither an sRGB nor an RGBA8 swapchain format");
    SPHXR_LOG_WARN("OpenXR: the runtime offers no sRGB swapchain format; using RGBA8 (colours will look too dark)");
  }
  if (options.wantDepth)
    for (int64_t f : formats)
      if (f == gl::kDepth32F || f == gl::kDepth24 || f == gl::kDepth16) {
        depthFormat = f;
        break;
      }

  uint32_t viewCount = 0;
  SPHXR_XR_CHECK(xrEnumerateViewConfigurationViews(instance, systemId, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0,
                                                   &viewCount, nullptr));
  if (viewCount != 2) return Status::Error(Format("OpenXR: expected 2 stereo views, the runtime has %u", viewCount));
  std::vector<XrViewConfigurationView> views(viewCount, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
  SPHXR_XR_CHECK(xrEnumerateViewConfigurationViews(instance, systemId, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO,
                                                   viewCount, &viewCount, views.data()));
  auto images = [&](XrSwapchain sc, std::vector<uint32_t>* out) -> Status {
    uint32_t n = 0;
    SPHXR_XR_CHECK(xrEnumerateSwapchainImages(sc, 0, &n, nullptr));
    std::vector<XrSwapchainImageOpenGLKHR> imgs(n, {XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR});
    SPHXR_XR_CHECK(xrEnumerateSwapchainImages(sc, n, &n, reinterpret_cast<XrSwapchainImageBaseHeader*>(imgs.data())));
    for (auto& i : imgs) out->push_back(i.image);
    return Status::Ok();
  };
  for (int e = 0; e < 2; ++e) {
    Eye& eye = eyes[size_t(e)];
    eye.width = int(views[size_t(e)].recommendedImageRectWidth);
    eye.height = int(views[size_t(e)].recommendedImageRectHeight);
    XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    ci.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_SAMPLED_BIT;
    ci.format = colorFormat;
    ci.sampleCount = 1;
    ci.width = uint32_t(eye.width);
    ci.height = uint32_t(eye.height);
    ci.faceCount = 1;
    ci.arraySize = 1;
    ci.mipCount = 1;
    SPHXR_XR_CHECK(xrCreateSwapchain(session, &ci, &eye.color));
    if (Status s = images(eye.color, &eye.colorImages); !s) return s;
    if (depthFormat) {
      ci.usageFlags = XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
      ci.format = depthFormat;
      SPHXR_XR_CHECK(xrCreateSwapchain(session, &ci, &eye.depth));
      if (Status s = images(eye.depth, &eye.depthImages); !s) return s;
    } else if (options.wantDepth) {
      gl.GenTextures(1, &eye.ownDepth);
      gl.BindTexture(gl::kTexture2D, eye.ownDepth);
      gl.TexImage2D(gl::kTexture2D, 0, int(gl::kDepth24), eye.width, eye.height, 0, gl::kDepthComponent, gl::kFloat,
                    nullptr);
      gl.BindTexture(gl::kTexture2D, 0);
    }
    gl.GenFramebuffers(1, &eye.framebuffer);
  }
  return Status::Ok();
}

}  // namespace sphxr::xr
