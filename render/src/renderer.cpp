#include "sphxr/render/renderer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "shaders.h"
#include "sphxr/render/interop.h"
#include "sphxr/common/log.h"

namespace sphxr::render {
namespace {

/// std140 layout of ViewBlock in shaders.h.
struct ViewUniforms {
  glm::mat4 view, proj, viewProj, invViewProj;
  glm::vec4 eye, sun, viewport, absorption, waterColor, particle;
};

struct ErrorSink {
  GlErrorHandler handler;
  std::atomic<int> count{0};
};

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

GLuint Compile(GLenum stage, std::initializer_list<const char*> parts, std::string* log) {
  std::vector<const char*> sources(parts);
  GLuint shader = glCreateShader(stage);
  glShaderSource(shader, static_cast<GLsizei>(sources.size()), sources.data(), nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char buffer[4096];
    glGetShaderInfoLog(shader, sizeof(buffer), nullptr, buffer);
    *log += buffer;
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

Status Link(const char* name, std::initializer_list<const char*> vs, std::initializer_list<const char*> fs,
            GLuint* out) {
  std::string log;
  GLuint v = Compile(GL_VERTEX_SHADER, vs, &log);
  GLuint f = Compile(GL_FRAGMENT_SHADER, fs, &log);
  if (!v || !f) {
    glDeleteShader(v);
    glDeleteShader(f);
    for (char& c : log) c = (c == '\n') ? ' ' : c;  // one line
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
    return Status::Error(Format("shader %s does not link: %s", name, buffer));
  }
  *out = program;
  return Status::Ok();
}

/// Unit cube centred at the origin: 36 vertices of position + normal.
std::vector<float> CubeTriangles() {
  std::vector<float> v;
  const int faces[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 2, 0}, {1, 0, 2}, {2, 0, 1}, {2, 1, 0}};
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const float sign = (f % 2 == 0) ? 1.0f : -1.0f;
    (void)faces;
    // Two in-plane axes, ordered so that the winding is counter-clockwise seen from outside.
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const float corners[4][2] = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    const int order[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; ++k) {
      const int c = sign > 0 ? order[k] : order[5 - k];
      float p[3], n[3] = {0, 0, 0};
      p[axis] = 0.5f * sign;
      p[a] = corners[c][0];
      p[b] = corners[c][1];
      n[axis] = sign;
      v.insert(v.end(), {p[0], p[1], p[2], n[0], n[1], n[2]});
    }
  }
  return v;
}

/// The 12 edges of the unit cube centred at the origin, as 24 line vertices.
std::vector<float> CubeEdges() {
  std::vector<float> v;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int i = 0; i < 4; ++i) {
      float p[3];
      p[a] = (i & 1) ? 0.5f : -0.5f;
      p[b] = (i & 2) ? 0.5f : -0.5f;
      p[axis] = -0.5f;
      v.insert(v.end(), {p[0], p[1], p[2]});
      p[axis] = 0.5f;
      v.insert(v.end(), {p[0], p[1], p[2]});
    }
  }
  return v;
}

glm::mat4 BoxModel(const sim::Aabb& box) {
  const glm::vec3 lo(box.min.x, box.min.y, box.min.z), hi(box.max.x, box.max.y, box.max.z);
  return glm::scale(glm::translate(glm::mat4(1.0f), 0.5f * (lo + hi)), hi - lo);
}

/// A growable GL buffer.
struct Buffer {
  GLuint id = 0;
  size_t capacity = 0;
  void Upload(const void* data, size_t bytes) {
    if (bytes > capacity || id == 0) {
      if (id) glDeleteBuffers(1, &id);
      glCreateBuffers(1, &id);
      capacity = std::max<size_t>(bytes, 256) * 3 / 2;
      glNamedBufferStorage(id, capacity, nullptr, GL_DYNAMIC_STORAGE_BIT);
    }
    if (bytes > 0) glNamedBufferSubData(id, 0, bytes, data);
  }
  ~Buffer() {
    if (id) glDeleteBuffers(1, &id);
  }
};

}  // namespace

const char* ParticleColorName(ParticleColor c) {
  switch (c) {
    case ParticleColor::kSpeed: return "speed";
    case ParticleColor::kDensityError: return "density error";
    case ParticleColor::kActivity: return "reuse activity";
  }
  return "?";
}

const char* RenderModeName(RenderMode m) { return m == RenderMode::kWater ? "water" : "particles"; }

glm::vec3 SkyColor(glm::vec3 d, glm::vec3 sun) {
  const glm::vec3 horizon(0.80f, 0.87f, 0.95f), zenith(0.22f, 0.45f, 0.85f), ground(0.62f, 0.63f, 0.64f);
  const float t = std::clamp(d.y, -1.0f, 1.0f);
  glm::vec3 c = t >= 0.0f ? glm::mix(horizon, zenith, std::sqrt(t)) : glm::mix(horizon, ground, std::sqrt(-t));
  const float s = std::max(glm::dot(d, sun), 0.0f);
  c += glm::vec3(1.0f, 0.9f, 0.7f) * (4.0f * std::pow(s, 800.0f) + 0.15f * std::pow(s, 8.0f));
  return glm::clamp(c, 0.0f, 1.0f);
}

glm::mat4 Camera::View() const { return glm::lookAt(eye, target, up); }
glm::mat4 Camera::Projection(float aspect) const {
  return glm::perspective(fovYRadians, aspect, nearPlane, farPlane);
}

Camera FrameBox(const sim::Aabb& box, float aspect) {
  const glm::vec3 lo(box.min.x, box.min.y, box.min.z), hi(box.max.x, box.max.y, box.max.z);
  Camera c;
  c.target = 0.5f * (lo + hi);
  const float radius = 0.5f * glm::length(hi - lo);
  const float halfFov = 0.5f * std::min(c.fovYRadians, 2.0f * std::atan(std::tan(0.5f * c.fovYRadians) * aspect));
  const float distance = 1.1f * radius / std::sin(halfFov);
  c.eye = c.target + distance * glm::normalize(glm::vec3(0.35f, 0.45f, 1.0f));
  c.nearPlane = std::max(1e-3f, 0.02f * distance);
  c.farPlane = 50.0f * distance;
  return c;
}

struct Renderer::Impl {
  ErrorSink sink;
  GLuint skyProgram = 0, solidProgram = 0, lineProgram = 0, meshProgram = 0, spriteProgram = 0;
  GLuint emptyVao = 0, solidVao = 0, lineVao = 0, meshVao = 0, spriteVao = 0;
  Buffer cube, edges, floorQuad, meshPositions, meshNormals, meshIndices, particles, uniforms;
  int cubeVertices = 0, edgeVertices = 0;
  // Thickness target, grown to the largest viewport seen.
  GLuint thicknessFbo = 0, thicknessTexture = 0;
  int thicknessW = 0, thicknessH = 0;
  std::vector<float> staging;
  // What the last upload holds.
  int meshVertexCount = 0, meshIndexCount = 0, particleCount = 0;
  bool hasMesh = false;

  ~Impl() {
    for (GLuint p : {skyProgram, solidProgram, lineProgram, meshProgram, spriteProgram}) glDeleteProgram(p);
    for (GLuint v : {emptyVao, solidVao, lineVao, meshVao, spriteVao}) glDeleteVertexArrays(1, &v);
    glDeleteFramebuffers(1, &thicknessFbo);
    glDeleteTextures(1, &thicknessTexture);
  }

  void EnsureThickness(int w, int h) {
    if (w <= thicknessW && h <= thicknessH && thicknessFbo) return;
    glDeleteFramebuffers(1, &thicknessFbo);
    glDeleteTextures(1, &thicknessTexture);
    thicknessW = std::max(w, thicknessW);
    thicknessH = std::max(h, thicknessH);
    glCreateTextures(GL_TEXTURE_2D, 1, &thicknessTexture);
    glTextureStorage2D(thicknessTexture, 1, GL_R32F, thicknessW, thicknessH);
    glTextureParameteri(thicknessTexture, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(thicknessTexture, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glCreateFramebuffers(1, &thicknessFbo);
    glNamedFramebufferTexture(thicknessFbo, GL_COLOR_ATTACHMENT0, thicknessTexture, 0);
  }
};

Renderer::Renderer(const RendererConfig& config) : m_config(config), m_impl(std::make_unique<Impl>()) {}

Renderer::~Renderer() {
  if (m_config.debug) glDebugMessageCallback(nullptr, nullptr);
}

int Renderer::ErrorCount() const { return m_impl->sink.count.load(); }

Status Renderer::Create(const RendererConfig& config, std::unique_ptr<Renderer>* out) {
  out->reset();
  if (!epoxy_is_desktop_gl() || epoxy_gl_version() < 45) {
    return Status::Error(Format("the renderer needs OpenGL 4.5 core; this context offers %s %d.%d (update the GPU "
                                "driver, or use Mesa's llvmpipe: LIBGL_ALWAYS_SOFTWARE=1)",
                                epoxy_is_desktop_gl() ? "OpenGL" : "OpenGL ES", epoxy_gl_version() / 10,
                                epoxy_gl_version() % 10));
  }
  std::unique_ptr<Renderer> r(new Renderer(config));
  Impl& m = *r->m_impl;
  if (config.debug) {
    m.sink.handler = config.onError;
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(DebugCallback, &m.sink);
    glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
  }
  using namespace shaders;
  if (Status s = Link("sky", {kCommon, kSkyVs}, {kCommon, kSkyFs}, &m.skyProgram); !s) return s;
  if (Status s = Link("solid", {kCommon, kSolidVs}, {kCommon, kSolidFs}, &m.solidProgram); !s) return s;
  if (Status s = Link("line", {kCommon, kLineVs}, {kCommon, kLineFs}, &m.lineProgram); !s) return s;
  if (Status s = Link("water mesh", {kCommon, kMeshVs}, {kCommon, kWaterShade, kMeshFs}, &m.meshProgram); !s) return s;
  if (Status s = Link("particles", {kCommon, kSpriteVs}, {kCommon, kWaterShade, kSpriteFs}, &m.spriteProgram); !s) {
    return s;
  }

  const std::vector<float> cube = CubeTriangles();
  m.cube.Upload(cube.data(), cube.size() * sizeof(float));
  m.cubeVertices = static_cast<int>(cube.size() / 6);
  const std::vector<float> edges = CubeEdges();
  m.edges.Upload(edges.data(), edges.size() * sizeof(float));
  m.edgeVertices = static_cast<int>(edges.size() / 3);
  const float quad[] = {-0.5f, 0, -0.5f, 0, 1, 0, 0.5f, 0, 0.5f, 0, 1, 0, 0.5f, 0, -0.5f, 0, 1, 0,
                        -0.5f, 0, -0.5f, 0, 1, 0, -0.5f, 0, 0.5f, 0, 1, 0, 0.5f, 0, 0.5f, 0, 1, 0};
  m.floorQuad.Upload(quad, sizeof(quad));
  m.uniforms.Upload(nullptr, sizeof(ViewUniforms));

  glCreateVertexArrays(1, &m.emptyVao);
  // Solids: interleaved position + normal in one binding (the VBO is chosen per draw).
  glCreateVertexArrays(1, &m.solidVao);
  glEnableVertexArrayAttrib(m.solidVao, 0);
  glEnableVertexArrayAttrib(m.solidVao, 1);
  glVertexArrayAttribFormat(m.solidVao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribFormat(m.solidVao, 1, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float));
  glVertexArrayAttribBinding(m.solidVao, 0, 0);
  glVertexArrayAttribBinding(m.solidVao, 1, 0);
  glCreateVertexArrays(1, &m.lineVao);
  glEnableVertexArrayAttrib(m.lineVao, 0);
  glVertexArrayAttribFormat(m.lineVao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(m.lineVao, 0, 0);
  glVertexArrayVertexBuffer(m.lineVao, 0, m.edges.id, 0, 3 * sizeof(float));
  // Water mesh and particles: buffers are (re)bound at upload.
  glCreateVertexArrays(1, &m.meshVao);
  glEnableVertexArrayAttrib(m.meshVao, 0);
  glEnableVertexArrayAttrib(m.meshVao, 1);
  glVertexArrayAttribFormat(m.meshVao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribFormat(m.meshVao, 1, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(m.meshVao, 0, 0);
  glVertexArrayAttribBinding(m.meshVao, 1, 1);
  glCreateVertexArrays(1, &m.spriteVao);
  glEnableVertexArrayAttrib(m.spriteVao, 0);
  glVertexArrayAttribFormat(m.spriteVao, 0, 4, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(m.spriteVao, 0, 0);

  SPHXR_LOG_DEBUG("renderer ready on %s", reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
  *out = std::move(r);
  return Status::Ok();
}

void Renderer::Draw(const FrameScene& scene, std::span<const View> views) {
  Impl& m = *m_impl;
  const auto t0 = std::chrono::steady_clock::now();

  // ---- 1 upload (once for all views) ----
  const bool deviceMesh = scene.deviceSurface != nullptr && scene.deviceSurface->VertexCount() > 0;
  m.hasMesh = deviceMesh || !scene.surface.Empty();
  if (deviceMesh) {  // no upload: the buffers were written in place (CUDA-GL interop)
    m.meshVertexCount = scene.deviceSurface->VertexCount();
    m.meshIndexCount = 0;
    glVertexArrayVertexBuffer(m.meshVao, 0, scene.deviceSurface->PositionBuffer(), 0, 3 * sizeof(float));
    glVertexArrayVertexBuffer(m.meshVao, 1, scene.deviceSurface->NormalBuffer(), 0, 3 * sizeof(float));
    glVertexArrayElementBuffer(m.meshVao, 0);
  } else if (m.hasMesh) {
    const MeshView& s = scene.surface;
    m.meshVertexCount = s.vertexCount;
    m.meshIndexCount = s.indices ? s.indexCount : 0;
    m.meshPositions.Upload(s.positions, sizeof(float) * 3 * s.vertexCount);
    if (s.normals) {
      m.meshNormals.Upload(s.normals, sizeof(float) * 3 * s.vertexCount);
    } else {
      m.staging.assign(3 * s.vertexCount, 0.0f);  // no normals: face up (a flat look, never black)
      for (int i = 0; i < s.vertexCount; ++i) m.staging[3 * i + 1] = 1.0f;
      m.meshNormals.Upload(m.staging.data(), sizeof(float) * m.staging.size());
    }
    if (m.meshIndexCount > 0) m.meshIndices.Upload(s.indices, sizeof(uint32_t) * m.meshIndexCount);
    glVertexArrayVertexBuffer(m.meshVao, 0, m.meshPositions.id, 0, 3 * sizeof(float));
    glVertexArrayVertexBuffer(m.meshVao, 1, m.meshNormals.id, 0, 3 * sizeof(float));
    glVertexArrayElementBuffer(m.meshVao, m.meshIndexCount > 0 ? m.meshIndices.id : 0);
  }
  const ParticleView& p = scene.particles;
  const bool drawParticles = p.count > 0 && p.position && (scene.mode == RenderMode::kParticles || !m.hasMesh);
  m.particleCount = drawParticles ? p.count : 0;
  if (drawParticles) {
    m.staging.resize(4 * static_cast<size_t>(p.count));
    for (int i = 0; i < p.count; ++i) {
      float s = 0.0f;
      switch (scene.particleColor) {
        case ParticleColor::kSpeed:
          if (p.velocity) {
            const sim::Vec4 v = p.velocity[i];
            s = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z) / p.speedScale;
          }
          break;
        case ParticleColor::kDensityError:
          if (p.density) s = std::abs(p.density[i] / p.restDensity - 1.0f) / p.densityErrorScale;
          break;
        case ParticleColor::kActivity:
          s = (p.idle && p.idle[i] >= 0) ? 0.0f : 1.0f;  // reusing: blue; computing: red
          break;
      }
      m.staging[4 * i + 0] = p.position[i].x;
      m.staging[4 * i + 1] = p.position[i].y;
      m.staging[4 * i + 2] = p.position[i].z;
      m.staging[4 * i + 3] = s;
    }
    m.particles.Upload(m.staging.data(), sizeof(float) * m.staging.size());
    glVertexArrayVertexBuffer(m.spriteVao, 0, m.particles.id, 0, 4 * sizeof(float));
  }
  const auto t1 = std::chrono::steady_clock::now();

  // ---- per view ----
  const glm::vec3 tankLo(scene.tank.min.x, scene.tank.min.y, scene.tank.min.z);
  const glm::vec3 tankHi(scene.tank.max.x, scene.tank.max.y, scene.tank.max.z);
  const float tankSize = std::max({tankHi.x - tankLo.x, tankHi.y - tankLo.y, tankHi.z - tankLo.z, 1e-3f});
  const bool water = scene.mode == RenderMode::kWater;
  const bool waterFromMesh = water && m.hasMesh;
  const bool waterFromSprites = water && !m.hasMesh && m.particleCount > 0;

  glEnable(GL_PROGRAM_POINT_SIZE);
  glEnable(GL_SCISSOR_TEST);
  for (const View& v : views) {
    if (v.width <= 0 || v.height <= 0) continue;
    ViewUniforms u;
    u.view = v.view;
    u.proj = v.projection;
    u.viewProj = v.projection * v.view;
    u.invViewProj = glm::inverse(u.viewProj);
    u.eye = glm::vec4(glm::vec3(glm::inverse(v.view)[3]), 1.0f);
    u.sun = glm::vec4(glm::normalize(m_config.sunDirection), 0.0f);
    u.viewport = glm::vec4(v.x, v.y, v.width, v.height);
    u.absorption = glm::vec4(m_config.waterAbsorption * scene.absorptionScale, 0.0f);
    u.waterColor = glm::vec4(m_config.waterColor, 1.0f);
    u.particle = glm::vec4(p.radius, 0.5f * v.projection[1][1] * v.height, 0.0f, 0.0f);
    glNamedBufferSubData(m.uniforms.id, 0, sizeof(u), &u);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, m.uniforms.id);

    glBindFramebuffer(GL_FRAMEBUFFER, v.framebuffer);
    glViewport(v.x, v.y, v.width, v.height);
    glScissor(v.x, v.y, v.width, v.height);
    glDepthMask(GL_TRUE);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glClearDepth(1.0);
    glClear(GL_DEPTH_BUFFER_BIT);
    glDisable(GL_BLEND);

    // 2 sky
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glUseProgram(m.skyProgram);
    glBindVertexArray(m.emptyVao);
    glDrawArrays(GL_TRIANGLES, 0, 3);

    // 3 opaque: floor, obstacles, solids
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glUseProgram(m.solidProgram);
    glBindVertexArray(m.solidVao);
    if (scene.drawFloor) {
      const float extent = 12.0f * tankSize;
      const glm::vec3 centre = 0.5f * (tankLo + tankHi);
      // A hair below the tank floor so the water's bottom never fights with it.
      const glm::mat4 model = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(centre.x, tankLo.y - 1e-4f * tankSize,
                                                                                     centre.z)),
                                         glm::vec3(extent, 1.0f, extent));
      glVertexArrayVertexBuffer(m.solidVao, 0, m.floorQuad.id, 0, 6 * sizeof(float));
      glProgramUniformMatrix4fv(m.solidProgram, 0, 1, GL_FALSE, glm::value_ptr(model));
      glProgramUniform4f(m.solidProgram, 1, 0.78f, 0.76f, 0.72f, 1.0f);
      glProgramUniform4f(m.solidProgram, 2, tankSize / 8.0f, 0.45f * extent, 0, 0);
      glDrawArrays(GL_TRIANGLES, 0, 6);
    }
    glVertexArrayVertexBuffer(m.solidVao, 0, m.cube.id, 0, 6 * sizeof(float));
    glProgramUniform4f(m.solidProgram, 2, 0, 0, 0, 0);
    for (const sim::Aabb& box : scene.obstacles) {
      const glm::mat4 model = BoxModel(box);
      glProgramUniformMatrix4fv(m.solidProgram, 0, 1, GL_FALSE, glm::value_ptr(model));
      glProgramUniform4f(m.solidProgram, 1, 0.55f, 0.52f, 0.50f, 1.0f);
      glDrawArrays(GL_TRIANGLES, 0, m.cubeVertices);
    }
    for (const SolidMesh& solid : scene.solids) {
      glProgramUniformMatrix4fv(m.solidProgram, 0, 1, GL_FALSE, glm::value_ptr(solid.model));
      glProgramUniform4f(m.solidProgram, 1, solid.color.r, solid.color.g, solid.color.b, 1.0f);
      if (solid.mesh.Empty()) {
        glDrawArrays(GL_TRIANGLES, 0, m.cubeVertices);
      } else {
        // Rare (paddle meshes are small): interleave into the staging buffer and draw unindexed.
        const MeshView& s = solid.mesh;
        const int n = s.indices ? s.indexCount : s.vertexCount;
        std::vector<float> tri(6 * static_cast<size_t>(n));
        for (int k = 0; k < n; ++k) {
          const uint32_t i = s.indices ? s.indices[k] : static_cast<uint32_t>(k);
          for (int c = 0; c < 3; ++c) {
            tri[6 * k + c] = s.positions[3 * i + c];
            tri[6 * k + 3 + c] = s.normals ? s.normals[3 * i + c] : (c == 1 ? 1.0f : 0.0f);
          }
        }
        Buffer tmp;
        tmp.Upload(tri.data(), tri.size() * sizeof(float));
        glVertexArrayVertexBuffer(m.solidVao, 0, tmp.id, 0, 6 * sizeof(float));
        glDrawArrays(GL_TRIANGLES, 0, n);
        glVertexArrayVertexBuffer(m.solidVao, 0, m.cube.id, 0, 6 * sizeof(float));
      }
    }
    if (scene.mode == RenderMode::kParticles && m.particleCount > 0) {
      glUseProgram(m.spriteProgram);
      glProgramUniform1i(m.spriteProgram, 3, 3);
      glBindVertexArray(m.spriteVao);
      glDrawArrays(GL_POINTS, 0, m.particleCount);
    }
    if (scene.drawTank) {
      glUseProgram(m.lineProgram);
      glBindVertexArray(m.lineVao);
      const glm::mat4 model = BoxModel(scene.tank);
      glProgramUniformMatrix4fv(m.lineProgram, 0, 1, GL_FALSE, glm::value_ptr(model));
      glProgramUniform4f(m.lineProgram, 1, 0.15f, 0.18f, 0.22f, 1.0f);
      glDrawArrays(GL_LINES, 0, m.edgeVertices);
    }

    // 4-5 water
    if (waterFromMesh || waterFromSprites) {
      const GLuint program = waterFromMesh ? m.meshProgram : m.spriteProgram;
      auto drawWater = [&]() {
        if (waterFromMesh) {
          glBindVertexArray(m.meshVao);
          if (m.meshIndexCount > 0) {
            glDrawElements(GL_TRIANGLES, m.meshIndexCount, GL_UNSIGNED_INT, nullptr);
          } else {
            glDrawArrays(GL_TRIANGLES, 0, m.meshVertexCount);
          }
        } else {
          glBindVertexArray(m.spriteVao);
          glDrawArrays(GL_POINTS, 0, m.particleCount);
        }
      };
      glUseProgram(program);
      // thickness
      m.EnsureThickness(v.width, v.height);
      glBindFramebuffer(GL_FRAMEBUFFER, m.thicknessFbo);
      glViewport(0, 0, v.width, v.height);
      glScissor(0, 0, v.width, v.height);
      glClearColor(0, 0, 0, 0);
      glClear(GL_COLOR_BUFFER_BIT);
      glDisable(GL_DEPTH_TEST);
      glDepthMask(GL_FALSE);
      glEnable(GL_BLEND);
      glBlendFunc(GL_ONE, GL_ONE);
      glProgramUniform1i(program, 3, 0);
      drawWater();
      // depth of the nearest water surface
      glBindFramebuffer(GL_FRAMEBUFFER, v.framebuffer);
      glViewport(v.x, v.y, v.width, v.height);
      glScissor(v.x, v.y, v.width, v.height);
      glDisable(GL_BLEND);
      glEnable(GL_DEPTH_TEST);
      glDepthMask(GL_TRUE);
      glDepthFunc(GL_LESS);
      glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      glProgramUniform1i(program, 3, 1);
      drawWater();
      // shade it: dst = colour + dst * transmission (dual-source blending)
      glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      glDepthMask(GL_FALSE);
      glDepthFunc(GL_LEQUAL);
      glEnable(GL_BLEND);
      glBlendFuncSeparate(GL_ONE, GL_SRC1_COLOR, GL_ZERO, GL_ONE);
      glBindTextureUnit(0, m.thicknessTexture);
      glProgramUniform1i(program, 3, 2);
      drawWater();
      glDisable(GL_BLEND);
      glDepthMask(GL_TRUE);
      glDepthFunc(GL_LESS);
    }
  }
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
  if (m_config.debug) {
    for (GLenum e = glGetError(); e != GL_NO_ERROR; e = glGetError()) {
      DebugCallback(GL_DEBUG_SOURCE_API, GL_DEBUG_TYPE_ERROR, e, GL_DEBUG_SEVERITY_HIGH, -1,
                    Format("glGetError 0x%x after Renderer::Draw", e).c_str(), &m.sink);
    }
  }
  const auto t2 = std::chrono::steady_clock::now();
  m_stats.uploadMs = std::chrono::duration<double, std::milli>(t1 - t0).count();
  m_stats.drawMs = std::chrono::duration<double, std::milli>(t2 - t1).count();
}

}  // namespace sphxr::render
