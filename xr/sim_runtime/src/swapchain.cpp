// Swapchains of the simulated headset: GL textures made in the application's context (the
// application calls these with its context current, as XR_KHR_opengl_enable requires), and the
// capture of submitted eye images to PNG; the depth layers chained to them (XR_KHR_composition_layer_depth).
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "runtime.h"

#ifndef GL_SRGB8_ALPHA8
#define GL_SRGB8_ALPHA8 0x8C43
#endif
#ifndef GL_DEPTH_COMPONENT32F
#define GL_DEPTH_COMPONENT32F 0x8CAC
#endif
#ifndef GL_DEPTH_COMPONENT24
#define GL_DEPTH_COMPONENT24 0x81A6
#endif
#ifndef GL_TEXTURE_BINDING_2D
#define GL_TEXTURE_BINDING_2D 0x8069
#endif

namespace sphxr::xr::simrt {
namespace {

constexpr uint32_t kImageCount = 3;
// In order of preference, as xrEnumerateSwapchainFormats requires.
constexpr int64_t kFormats[] = {GL_SRGB8_ALPHA8, GL_RGBA8, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT24};

bool IsDepth(int64_t f) { return f == GL_DEPTH_COMPONENT32F || f == GL_DEPTH_COMPONENT24; }

/// Makes the session's GL context current for the scope if the calling thread has another one.
class ContextScope {
 public:
  explicit ContextScope(const Session* s) : m_session(s) {
    m_prevContext = glXGetCurrentContext();
    if (m_prevContext != s->binding.glxContext) {
      m_prevDisplay = glXGetCurrentDisplay();
      m_prevDrawable = glXGetCurrentDrawable();
      glXMakeCurrent(s->binding.xDisplay, s->binding.glxDrawable, s->binding.glxContext);
      m_switched = true;
    }
  }
  ~ContextScope() {
    if (!m_switched) return;
    if (m_prevContext) glXMakeCurrent(m_prevDisplay, m_prevDrawable, m_prevContext);
    else glXMakeCurrent(m_session->binding.xDisplay, None, nullptr);
  }

 private:
  const Session* m_session;
  GLXContext m_prevContext = nullptr;
  Display* m_prevDisplay = nullptr;
  GLXDrawable m_prevDrawable = 0;
  bool m_switched = false;
};

bool WritePng(const std::string& path, int w, int h, const std::vector<uint8_t>& rgbaTopDown) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return false;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    return false;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < h; ++y) png_write_row(png, rgbaTopDown.data() + size_t(y) * w * 4);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(f) == 0;
}

#define SIMRT_SWAPCHAIN(handle, var)                                                   \
  Swapchain* var = Check<Swapchain>(handle, Tag::kSwapchain);                          \
  if (!var) return XR_ERROR_HANDLE_INVALID;                                            \
  if (var->session->instance->lost) return XR_ERROR_INSTANCE_LOST;                     \
  if (var->session->lost) return XR_ERROR_SESSION_LOST

}  // namespace

XrResult EnumerateSwapchainFormats(XrSession handle, uint32_t capacity, uint32_t* count, int64_t* formats) {
  std::lock_guard lock(Lock());
  Session* s = Check<Session>(handle, Tag::kSession);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  return TwoCall(capacity, count, uint32_t(std::size(kFormats)), [&](uint32_t i) { formats[i] = kFormats[i]; });
}

XrResult CreateSwapchain(XrSession handle, const XrSwapchainCreateInfo* info, XrSwapchain* out) {
  std::lock_guard lock(Lock());
  Session* s = Check<Session>(handle, Tag::kSession);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (std::find(std::begin(kFormats), std::end(kFormats), info->format) == std::end(kFormats))
    return XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED;
  if (info->width == 0 || info->height == 0 || info->width > 8192 || info->height > 8192 || info->sampleCount != 1 ||
      info->faceCount != 1 || info->arraySize != 1 || info->mipCount != 1)
    return XR_ERROR_FEATURE_UNSUPPORTED;  // the simulated headset makes plain 2D single-sample images
  auto sc = std::make_unique<Swapchain>();
  sc->session = s;
  sc->format = info->format;
  sc->width = info->width;
  sc->height = info->height;
  ContextScope scope(s);
  GLint prev = 0;
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &prev);
  sc->textures.resize(kImageCount);
  glGenTextures(kImageCount, sc->textures.data());
  for (GLuint tex : sc->textures) {
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    if (IsDepth(info->format))
      glTexImage2D(GL_TEXTURE_2D, 0, GLint(info->format), GLsizei(info->width), GLsizei(info->height), 0,
                   GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    else
      glTexImage2D(GL_TEXTURE_2D, 0, GLint(info->format), GLsizei(info->width), GLsizei(info->height), 0, GL_RGBA,
                   GL_UNSIGNED_BYTE, nullptr);
  }
  glBindTexture(GL_TEXTURE_2D, GLuint(prev));
  if (glGetError() != GL_NO_ERROR) {
    glDeleteTextures(kImageCount, sc->textures.data());
    return XR_ERROR_RUNTIME_FAILURE;
  }
  *out = reinterpret_cast<XrSwapchain>(sc.get());
  s->swapchains.push_back(std::move(sc));
  return XR_SUCCESS;
}

XrResult DestroySwapchain(XrSwapchain handle) {
  std::lock_guard lock(Lock());
  Swapchain* sc = Check<Swapchain>(handle, Tag::kSwapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  Session* s = sc->session;
  if (glXGetCurrentContext() == s->binding.glxContext) glDeleteTextures(GLsizei(sc->textures.size()), sc->textures.data());
  sc->tag = Tag::kDead;
  std::erase_if(s->swapchains, [&](const std::unique_ptr<Swapchain>& p) { return p.get() == sc; });
  return XR_SUCCESS;
}

XrResult EnumerateSwapchainImages(XrSwapchain handle, uint32_t capacity, uint32_t* count,
                                  XrSwapchainImageBaseHeader* images) {
  std::lock_guard lock(Lock());
  SIMRT_SWAPCHAIN(handle, sc);
  if (capacity > 0 && images[0].type != XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR) return XR_ERROR_VALIDATION_FAILURE;
  auto* gl = reinterpret_cast<XrSwapchainImageOpenGLKHR*>(images);
  return TwoCall(capacity, count, uint32_t(sc->textures.size()), [&](uint32_t i) { gl[i].image = sc->textures[i]; });
}

XrResult AcquireSwapchainImage(XrSwapchain handle, const XrSwapchainImageAcquireInfo*, uint32_t* index) {
  std::lock_guard lock(Lock());
  SIMRT_SWAPCHAIN(handle, sc);
  if (sc->acquired.size() >= sc->textures.size()) return XR_ERROR_CALL_ORDER_INVALID;
  *index = sc->nextIndex;
  sc->acquired.push_back(sc->nextIndex);
  sc->nextIndex = (sc->nextIndex + 1) % sc->textures.size();
  return XR_SUCCESS;
}

XrResult WaitSwapchainImage(XrSwapchain handle, const XrSwapchainImageWaitInfo*) {
  std::lock_guard lock(Lock());
  SIMRT_SWAPCHAIN(handle, sc);
  if (sc->acquired.empty() || sc->waited) return XR_ERROR_CALL_ORDER_INVALID;
  sc->waited = true;  // images are never in use by the (absent) compositor: no wait
  return XR_SUCCESS;
}

XrResult ReleaseSwapchainImage(XrSwapchain handle, const XrSwapchainImageReleaseInfo*) {
  std::lock_guard lock(Lock());
  SIMRT_SWAPCHAIN(handle, sc);
  if (sc->acquired.empty() || !sc->waited) return XR_ERROR_CALL_ORDER_INVALID;
  sc->lastReleased = int(sc->acquired.front());
  sc->acquired.pop_front();
  sc->waited = false;
  return XR_SUCCESS;
}

void CaptureFrame(Session* s, const XrCompositionLayerProjection& layer) {
  ContextScope scope(s);
  GLint prevTex = 0, prevAlign = 0;
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &prevTex);
  glGetIntegerv(GL_PACK_ALIGNMENT, &prevAlign);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  for (uint32_t v = 0; v < layer.viewCount; ++v) {
    const XrSwapchainSubImage& sub = layer.views[v].subImage;
    auto* sc = reinterpret_cast<Swapchain*>(sub.swapchain);
    std::vector<uint8_t> full(size_t(sc->width) * sc->height * 4);
    glBindTexture(GL_TEXTURE_2D, sc->textures[size_t(sc->lastReleased)]);
    // Raw texel bytes: for an sRGB texture these are the encoded values a display would show.
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, full.data());
    const XrRect2Di& r = sub.imageRect;
    std::vector<uint8_t> out(size_t(r.extent.width) * r.extent.height * 4);
    for (int y = 0; y < r.extent.height; ++y) {
      int srcRow = r.offset.y + (r.extent.height - 1 - y);  // GL rows run bottom-up, PNG rows top-down
      std::memcpy(&out[size_t(y) * r.extent.width * 4], &full[(size_t(srcRow) * sc->width + r.offset.x) * 4],
                  size_t(r.extent.width) * 4);
    }
    char name[64];
    std::snprintf(name, sizeof name, "/frame_%06ld_%s.png", s->framesEnded, v == 0 ? "left" : "right");
    std::string path = s->instance->config.captureDir + name;
    if (!s->instance->captureFailed && !WritePng(path, r.extent.width, r.extent.height, out)) {
      std::fprintf(stderr, "sphxr simulated headset: cannot write '%s': no more frames are captured\n",
                   Shown(path).c_str());
      s->instance->captureFailed = true;
    }
  }
  glPixelStorei(GL_PACK_ALIGNMENT, prevAlign);
  glBindTexture(GL_TEXTURE_2D, GLuint(prevTex));
}

}  // namespace sphxr::xr::simrt

namespace sphxr::xr::simrt {

XrResult CheckDepthLayers(Session* s, const XrCompositionLayerProjection& layer, bool views[2]) {
  for (uint32_t v = 0; v < layer.viewCount && v < 2; ++v) {
    views[v] = false;
    for (auto* next = static_cast<const XrBaseInStructure*>(layer.views[v].next); next; next = next->next) {
      if (next->type != XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR) continue;
      if (!s->instance->depthLayersEnabled) return XR_ERROR_VALIDATION_FAILURE;  // extension not enabled
      const auto* d = reinterpret_cast<const XrCompositionLayerDepthInfoKHR*>(next);
      auto* sc = Check<Swapchain>(d->subImage.swapchain, Tag::kSwapchain);
      if (!sc) return XR_ERROR_HANDLE_INVALID;
      if (!IsDepth(sc->format) || sc->lastReleased < 0) return XR_ERROR_LAYER_INVALID;
      const XrRect2Di& r = d->subImage.imageRect;
      if (r.offset.x < 0 || r.offset.y < 0 || r.extent.width <= 0 || r.extent.height <= 0 ||
          uint32_t(r.offset.x + r.extent.width) > sc->width || uint32_t(r.offset.y + r.extent.height) > sc->height)
        return XR_ERROR_SWAPCHAIN_RECT_INVALID;
      // The extension's valid usage: depths in [0, 1], min below max, finite distinct planes.
      if (!(d->minDepth >= 0.0f && d->maxDepth <= 1.0f && d->minDepth < d->maxDepth) ||
          !(std::isfinite(d->nearZ) && std::isfinite(d->farZ) && d->nearZ != d->farZ && d->nearZ >= 0 && d->farZ >= 0))
        return XR_ERROR_VALIDATION_FAILURE;
      views[v] = true;
    }
  }
  return XR_SUCCESS;
}

void RecordDepthLayers(Session* s, const XrCompositionLayerProjection& layer, const bool views[2]) {
  const std::string path = s->instance->config.captureDir + "/depth_layers.txt";
  FILE* f = std::fopen(path.c_str(), "a");
  if (!f) return;  // the colour capture already said the folder cannot be written
  ContextScope scope(s);
  GLint prevTex = 0, prevAlign = 0;
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &prevTex);
  glGetIntegerv(GL_PACK_ALIGNMENT, &prevAlign);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  for (uint32_t v = 0; v < layer.viewCount && v < 2; ++v) {
    const char* eye = v == 0 ? "left" : "right";
    if (!views[v]) {
      std::fprintf(f, "frame %ld %s depth none\n", s->framesEnded, eye);
      continue;
    }
    const XrCompositionLayerDepthInfoKHR* d = nullptr;
    for (auto* next = static_cast<const XrBaseInStructure*>(layer.views[v].next); next; next = next->next) {
      if (next->type == XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR) d = reinterpret_cast<const XrCompositionLayerDepthInfoKHR*>(next);
    }
    auto* sc = reinterpret_cast<Swapchain*>(d->subImage.swapchain);
    std::vector<float> depth(size_t(sc->width) * sc->height);
    glBindTexture(GL_TEXTURE_2D, sc->textures[size_t(sc->lastReleased)]);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    float nearest = 1.0f;
    size_t covered = 0;
    for (float z : depth) {
      nearest = std::min(nearest, z);
      covered += z < 1.0f;
    }
    // The depth image itself, as raw 32-bit floats with rows top-down like the colour PNG.
    const XrRect2Di& r = d->subImage.imageRect;
    char name[80];
    std::snprintf(name, sizeof name, "/frame_%06ld_%s_depth.f32", s->framesEnded, eye);
    if (FILE* raw = std::fopen((s->instance->config.captureDir + name).c_str(), "wb")) {
      for (int y = 0; y < r.extent.height; ++y) {
        const int row = r.offset.y + (r.extent.height - 1 - y);
        std::fwrite(&depth[size_t(row) * sc->width + size_t(r.offset.x)], sizeof(float), size_t(r.extent.width), raw);
      }
      std::fclose(raw);
    }
    std::fprintf(f, "frame %ld %s depth %ux%u near %g far %g nearest %.6f covered %.4f\n", s->framesEnded, eye,
                 unsigned(d->subImage.imageRect.extent.width), unsigned(d->subImage.imageRect.extent.height), d->nearZ,
                 d->farZ, nearest, double(covered) / double(depth.size()));
  }
  glPixelStorei(GL_PACK_ALIGNMENT, prevAlign);
  glBindTexture(GL_TEXTURE_2D, GLuint(prevTex));
  std::fclose(f);
}

}  // namespace sphxr::xr::simrt
