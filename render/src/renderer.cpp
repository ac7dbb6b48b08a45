#include "sphxr/render/renderer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "frame_targets.h"
#include "gl_util.h"
#include "pass_timer.h"
#include "passes/frame_data.h"
#include "passes/passes.h"
#include "sphxr/common/log.h"

namespace sphxr::render {

const char* ParticleColorName(ParticleColor c) {
  switch (c) {
    case ParticleColor::kSpeed: return "speed";
    case ParticleColor::kDensityError: return "density error";
    case ParticleColor::kActivity: return "reuse activity";
  }
  return "?";
}

const char* RenderModeName(RenderMode m) { return m == RenderMode::kWater ? "water" : "particles"; }

const char* RenderQualityName(RenderQuality q) {
  switch (q) {
    case RenderQuality::kLow: return "low";
    case RenderQuality::kMedium: return "medium";
    case RenderQuality::kHigh: return "high";
  }
  return "?";
}

bool ParseRenderQuality(const std::string& text, RenderQuality* out) {
  for (RenderQuality q : {RenderQuality::kLow, RenderQuality::kMedium, RenderQuality::kHigh}) {
    if (text == RenderQualityName(q)) {
      *out = q;
      return true;
    }
  }
  return false;
}

RenderSettings SettingsFor(RenderQuality q) {
  RenderSettings s;
  switch (q) {
    case RenderQuality::kLow:
      s.shadowMapSize = 0;
      s.diffuse = false;
      break;
    case RenderQuality::kMedium:
      s.shadowMapSize = 1024;
      break;
    case RenderQuality::kHigh:
      s.shadowMapSize = 2048;
      break;
  }
  return s;
}

double DrawStats::GpuMs() const {
  double sum = 0.0;
  for (const PassTime& p : passes) sum += p.gpuMs;
  return sum;
}

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
  explicit Impl(bool finishEachPass) : timer(finishEachPass) {}
  ErrorSink sink;
  RenderSettings settings;
  FrameData data;
  uint64_t uploadedKey = 0;  // FrameScene::frameKey of the last upload
  int timedViews = -1;       // views drawn in the pass timer's open frame (-1: none open)
  FrameTargets targets;
  PassTimer timer;
  SkyPass sky;
  ShadowPass shadow;
  OpaquePass opaque;
  GlassPass glass;
  DiffusePass diffuse;
  WaterThicknessPass thickness;
  PresentPass present;
  WaterPass water;

  Status Create() {
    for (Status s : {sky.Create(), shadow.Create(), opaque.Create(), glass.Create(), diffuse.Create(),
                     thickness.Create(), present.Create(), water.Create()}) {
      if (!s) return s;
    }
    return Status::Ok();
  }
};

Renderer::Renderer(const RendererConfig& config) : m_config(config), m_impl(std::make_unique<Impl>(config.finishEachPass)) {
  m_impl->settings = SettingsFor(config.quality);
}

Renderer::~Renderer() {
  m_impl.reset();
  if (m_config.debug) glDebugMessageCallback(nullptr, nullptr);
}

int Renderer::ErrorCount() const { return m_impl->sink.count.load(); }

void Renderer::SetQuality(RenderQuality quality) {
  m_config.quality = quality;
  m_impl->settings = SettingsFor(quality);
  m_impl->uploadedKey = 0;  // the next frame uploads and casts its shadows at the new settings
}

Status Renderer::Create(const RendererConfig& config, std::unique_ptr<Renderer>* out) {
  out->reset();
  if (!epoxy_is_desktop_gl() || epoxy_gl_version() < 45) {
    return Status::Error(Format("the renderer needs OpenGL 4.5 core; this context offers %s %d.%d (update the GPU "
                                "driver, or use Mesa's llvmpipe: LIBGL_ALWAYS_SOFTWARE=1)",
                                epoxy_is_desktop_gl() ? "OpenGL" : "OpenGL ES", epoxy_gl_version() / 10,
                                epoxy_gl_version() % 10));
  }
  if (!(config.waterIor >= 1.0f && config.waterIor <= 3.0f)) {
    return Status::Error(Format("the water's index of refraction %g is out of range: must be from 1 to 3",
                                static_cast<double>(config.waterIor)));
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
  if (Status s = m.Create(); !s) return s;
  SPHXR_LOG_DEBUG("renderer ready on %s", reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
  *out = std::move(r);
  return Status::Ok();
}

void Renderer::Draw(const FrameScene& scene, std::span<const View> views) {
  Impl& m = *m_impl;
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  // Once for all views, and once for the calls that draw the views of one frame (FrameScene::frameKey).
  const bool sameFrame = scene.frameKey != 0 && scene.frameKey == m.uploadedKey;
  if (!sameFrame) m.data.Upload(scene, m.settings);
  m.uploadedKey = scene.frameKey;
  const auto t1 = Clock::now();
  auto timed = [&](const char* name, auto&& pass) {
    PassTimer::Scope scope(&m.timer, name);
    pass();
  };

  // The pass times of a frame: one call, or the calls that share its frameKey (the frame then ends
  // when the next one's first call begins).
  if (!sameFrame) {
    if (m.timedViews >= 0) m.timer.EndFrame(m.timedViews, &m_stats);
    m.timer.BeginFrame();
    m.timedViews = 0;
  }
  glEnable(GL_SCISSOR_TEST);
  glEnable(GL_PROGRAM_POINT_SIZE);  // sprites size themselves
  int drawn = 0;
  for (const View& v : views) {
    if (v.width <= 0 || v.height <= 0) continue;
    m.targets.EnsureView(v.width, v.height);
    m.data.BindView(scene, v, m_config, glm::vec2(m.targets.Width(), m.targets.Height()));
    const PassContext ctx{scene, v, m.data, m.targets, m.settings};
    if (drawn++ == 0 && !sameFrame) timed("shadow", [&] { m.shadow.Run(m.data, m.targets, m.settings); });
    // Into the frame targets: the opaque scene, kept as textures.
    BeginScene(ctx);
    timed("opaque", [&] { m.opaque.Run(ctx); });
    timed("sky", [&] { m.sky.Run(ctx); });
    timed("glass", [&] { m.glass.RunFar(ctx); });
    timed("bubbles", [&] { m.diffuse.RunBubbles(ctx); });
    timed("water thickness", [&] { m.thickness.Run(ctx); });
    // Into the view: the opaque scene, the water over it, the near glass, spray and foam.
    BeginViewFramebuffer(ctx);
    timed("present", [&] { m.present.Run(ctx); });
    timed("water", [&] { m.water.Run(ctx); });
    timed("glass", [&] { m.glass.RunNear(ctx); });
    timed("spray and foam", [&] { m.diffuse.RunSprayAndFoam(ctx); });
  }
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
  m.timedViews += drawn;
  if (scene.frameKey == 0) {
    m.timer.EndFrame(m.timedViews, &m_stats);
    m.timedViews = -1;
  }
  if (m_config.debug) {
    for (GLenum e = glGetError(); e != GL_NO_ERROR; e = glGetError()) {
      DebugCallback(GL_DEBUG_SOURCE_API, GL_DEBUG_TYPE_ERROR, e, GL_DEBUG_SEVERITY_HIGH, -1,
                    Format("glGetError 0x%x after Renderer::Draw", e).c_str(), &m.sink);
    }
  }
  const auto t2 = Clock::now();
  m_stats.uploadMs = std::chrono::duration<double, std::milli>(t1 - t0).count();
  m_stats.drawMs = std::chrono::duration<double, std::milli>(t2 - t1).count();
}

}  // namespace sphxr::render
