#pragma once
// Small OpenGL helpers shared by the renderer's passes: the debug-message sink, program linking from
// the sources in shaders.h, and a growable buffer.
#include <epoxy/gl.h>

#include <atomic>
#include <cstddef>
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/render/renderer.h"

namespace sphxr::render {

/// Where GL errors go (RendererConfig::onError, or log and abort without a handler).
struct ErrorSink {
  GlErrorHandler handler;
  std::atomic<int> count{0};
};
void GLAPIENTRY DebugCallback(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                              const GLchar* message, const void* user);

/// Links the program named `name` in shaders::Programs(); one line naming the program on failure.
Status LinkProgram(const char* name, GLuint* out);

/// A growable GL buffer (never shrinks).
struct Buffer {
  GLuint id = 0;
  size_t capacity = 0;
  void Upload(const void* data, size_t bytes);
  ~Buffer();
};

/// A GL object name released with its deleter when the owner goes.
struct Program {
  GLuint id = 0;
  ~Program() {
    if (id) glDeleteProgram(id);
  }
};

}  // namespace sphxr::render
