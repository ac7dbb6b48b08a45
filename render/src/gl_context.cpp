// EGL surfaceless context and offscreen framebuffers. GL and EGL entry points come from libepoxy,
// which resolves them per context at run time (the same code then works under GLFW's GLX context).
#include "sphxr/render/gl_context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "sphxr/common/log.h"

namespace sphxr::render {
namespace {

bool HasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

}  // namespace

Status HeadlessContext::Create(bool debug, std::unique_ptr<HeadlessContext>* out) {
  out->reset();
  const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  EGLDisplay display = EGL_NO_DISPLAY;
  if (HasExtension(clientExtensions, "EGL_MESA_platform_surfaceless") && HasExtension(clientExtensions, "EGL_EXT_platform_base")) {
    display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  }
  if (display == EGL_NO_DISPLAY) {
    SPHXR_LOG_INFO("EGL: no surfaceless platform, trying the default display");
    display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  }
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
    return Status::Error(Format("no EGL display for headless OpenGL (eglInitialize error 0x%x); install Mesa's EGL "
                                "(libegl-mesa0)", eglGetError()));
  }
  const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                  EGL_RED_SIZE,     8,               EGL_GREEN_SIZE,      8,
                                  EGL_BLUE_SIZE,    8,               EGL_DEPTH_SIZE,      24,
                                  EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(display, configAttribs, &config, 1, &count) || count < 1) {
    eglTerminate(display);
    return Status::Error("EGL: no OpenGL config with a pbuffer surface type");
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(display);
    return Status::Error("EGL: the OpenGL API is not available (only GLES?)");
  }
  const EGLint contextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                   4,
                                   EGL_CONTEXT_MINOR_VERSION,
                                   5,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                   EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                   EGL_CONTEXT_OPENGL_DEBUG,
                                   debug ? EGL_TRUE : EGL_FALSE,
                                   EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttribs);
  if (context == EGL_NO_CONTEXT) {
    eglTerminate(display);
    return Status::Error(Format("OpenGL 4.5 core is not available through EGL (eglCreateContext error 0x%x); the "
                                "renderer needs GL 4.5 (Mesa llvmpipe has it)", eglGetError()));
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    eglTerminate(display);
    return Status::Error("EGL: cannot make a surfaceless context current (EGL_KHR_surfaceless_context missing)");
  }
  std::unique_ptr<HeadlessContext> ctx(new HeadlessContext());
  ctx->m_display = display;
  ctx->m_context = context;
  SPHXR_LOG_DEBUG("headless OpenGL: %s", GlDescription());
  *out = std::move(ctx);
  return Status::Ok();
}

HeadlessContext::~HeadlessContext() {
  if (!m_display) return;
  eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (m_context) eglDestroyContext(m_display, m_context);
  eglTerminate(m_display);
}

void HeadlessContext::MakeCurrent() { eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_context); }

void Image::FlipRows() {
  const size_t row = 4 * static_cast<size_t>(width);
  for (int y = 0; y < height / 2; ++y) {
    std::swap_ranges(rgba.begin() + y * row, rgba.begin() + (y + 1) * row, rgba.begin() + (height - 1 - y) * row);
  }
}

Status OffscreenTarget::Create(int width, int height, std::unique_ptr<OffscreenTarget>* out) {
  out->reset();
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    return Status::Error(Format("image size %dx%d: must be from 1x1 to 16384x16384", width, height));
  }
  std::unique_ptr<OffscreenTarget> t(new OffscreenTarget());
  t->m_width = width;
  t->m_height = height;
  glCreateTextures(GL_TEXTURE_2D, 1, &t->m_color);
  glTextureStorage2D(t->m_color, 1, GL_RGBA8, width, height);
  glCreateRenderbuffers(1, &t->m_depth);
  glNamedRenderbufferStorage(t->m_depth, GL_DEPTH_COMPONENT24, width, height);
  glCreateFramebuffers(1, &t->m_fbo);
  glNamedFramebufferTexture(t->m_fbo, GL_COLOR_ATTACHMENT0, t->m_color, 0);
  glNamedFramebufferRenderbuffer(t->m_fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->m_depth);
  const GLenum status = glCheckNamedFramebufferStatus(t->m_fbo, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    return Status::Error(Format("offscreen framebuffer %dx%d incomplete (0x%x)", width, height, status));
  }
  *out = std::move(t);
  return Status::Ok();
}

OffscreenTarget::~OffscreenTarget() {
  glDeleteFramebuffers(1, &m_fbo);
  glDeleteRenderbuffers(1, &m_depth);
  glDeleteTextures(1, &m_color);
}

Image OffscreenTarget::Read() const { return ReadPixels(m_fbo, 0, 0, m_width, m_height); }

std::vector<float> OffscreenTarget::ReadDepth() const {
  std::vector<float> depth(static_cast<size_t>(m_width) * m_height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m_fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, m_width, m_height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  return depth;
}

Image ReadPixels(uint32_t framebuffer, int x, int y, int width, int height) {
  Image image;
  image.width = width;
  image.height = height;
  image.rgba.resize(4 * static_cast<size_t>(width) * height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(x, y, width, height, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

const char* GlDescription() {
  static thread_local std::string text;
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  text = std::string(version ? version : "?") + ", " + (renderer ? renderer : "?");
  return text.c_str();
}

}  // namespace sphxr::render
