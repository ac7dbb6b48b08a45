#pragma once
// The few GL entry points xr/ calls, loaded through the application's getProcAddress (xr brings no
// GL loader of its own, so it never fights the renderer's).
#include <cstdint>

namespace sphxr::xr {

struct GlFunctions {
  using GLenum = unsigned int;
  using GLuint = unsigned int;
  using GLint = int;
  using GLsizei = int;
  void (*GenFramebuffers)(GLsizei, GLuint*) = nullptr;
  void (*DeleteFramebuffers)(GLsizei, const GLuint*) = nullptr;
  void (*BindFramebuffer)(GLenum, GLuint) = nullptr;
  void (*FramebufferTexture2D)(GLenum, GLenum, GLenum, GLuint, GLint) = nullptr;
  GLenum (*CheckFramebufferStatus)(GLenum) = nullptr;
  void (*Viewport)(GLint, GLint, GLsizei, GLsizei) = nullptr;
  void (*GetIntegerv)(GLenum, GLint*) = nullptr;
  const unsigned char* (*GetString)(GLenum) = nullptr;
  void (*GenTextures)(GLsizei, GLuint*) = nullptr;
  void (*DeleteTextures)(GLsizei, const GLuint*) = nullptr;
  void (*BindTexture)(GLenum, GLuint) = nullptr;
  void (*TexImage2D)(GLenum, GLint, GLint, GLsizei, GLsizei, GLint, GLenum, GLenum, const void*) = nullptr;
  void (*Enable)(GLenum) = nullptr;
  void (*Disable)(GLenum) = nullptr;
  unsigned char (*IsEnabled)(GLenum) = nullptr;

  /// False (with the missing name) when an entry point cannot be loaded.
  bool Load(void* (*getProcAddress)(const char*), const char** missing);
};

namespace gl {
constexpr unsigned kFramebuffer = 0x8D40, kDrawFramebufferBinding = 0x8CA6, kColorAttachment0 = 0x8CE0,
                   kDepthAttachment = 0x8D00, kFramebufferComplete = 0x8CD5, kTexture2D = 0x0DE1,
                   kVersion = 0x1F02, kFramebufferSrgb = 0x8DB9, kSrgb8Alpha8 = 0x8C43, kSrgb8 = 0x8C41,
                   kRgba8 = 0x8058, kDepth32F = 0x8CAC, kDepth24 = 0x81A6, kDepth16 = 0x81A5,
                   kDepthComponent = 0x1902, kFloat = 0x1406, kTextureBinding2D = 0x8069;
}

}  // namespace sphxr::xr
