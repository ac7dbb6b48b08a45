#include "gl_util.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "shaders.h"
#include "sphxr/common/log.h"

namespace sphxr::render {

void GLAPIENTRY DebugCallback(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                              const GLchar* message, const void* user) {
  (void)source;
  (void)length;
  auto* sink = static_cast<ErrorSink*>(const_cast<void*>(user));
  if (type != GL_DEBUG_TYPE_ERROR) {
    if (severity == GL_DEBUG_SEVERITY_HIGH) LogOnce("gl-debug-high", LogLevel::kWarn, "GL: %s", message);
    return;
  }
  ++sink->count;
  const std::string text = Format("GL error (id %u): %s", id, message);
  if (sink->handler) {
    sink->handler(text);
    return;
  }
  SPHXR_LOG_ERROR("%s", text.c_str());
  std::abort();  // a debug build fails loudly at the call that erred (the callback is synchronous)
}

namespace {

/// A shader or program info log as one line.
std::string OneLine(const char* log) {
  std::string text(log);
  for (char& c : text) c = (c == '\n') ? ' ' : c;
  return text;
}

GLuint Compile(GLenum stage, const std::vector<const char*>& parts, std::string* log) {
  GLuint shader = glCreateShader(stage);
  glShaderSource(shader, static_cast<GLsizei>(parts.size()), parts.data(), nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char buffer[4096];
    glGetShaderInfoLog(shader, sizeof(buffer), nullptr, buffer);
    *log += OneLine(buffer);
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

}  // namespace

Status LinkProgram(const char* name, GLuint* out) {
  const auto& programs = shaders::Programs();
  const auto it = std::find_if(programs.begin(), programs.end(),
                               [&](const shaders::ProgramSource& p) { return std::strcmp(p.name, name) == 0; });
  if (it == programs.end()) return Status::Error(Format("shader program '%s' is not in shaders.h", name));
  std::string log;
  GLuint v = Compile(GL_VERTEX_SHADER, it->vertex, &log);
  GLuint f = Compile(GL_FRAGMENT_SHADER, it->fragment, &log);
  if (!v || !f) {
    glDeleteShader(v);
    glDeleteShader(f);
    return Status::Error(Format("shader %s does not compile: %s", name, log.c_str()));
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, v);
  glAttachShader(program, f);
  glLinkProgram(program);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char buffer[4096];
    glGetProgramInfoLog(program, sizeof(buffer), nullptr, buffer);
    glDeleteProgram(program);
    return Status::Error(Format("shader %s does not link: %s", name, OneLine(buffer).c_str()));
  }
  *out = program;
  return Status::Ok();
}

void Buffer::Upload(const void* data, size_t bytes) {
  if (bytes > capacity || id == 0) {
    if (id) glDeleteBuffers(1, &id);
    glCreateBuffers(1, &id);
    capacity = std::max<size_t>(bytes, 256) * 3 / 2;
    glNamedBufferStorage(id, static_cast<GLsizeiptr>(capacity), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  if (bytes > 0 && data) glNamedBufferSubData(id, 0, static_cast<GLsizeiptr>(bytes), data);
}

Buffer::~Buffer() {
  if (id) glDeleteBuffers(1, &id);
}

}  // namespace sphxr::render
