#pragma once
// Shared by the render tests: a headless GL context with the debug callback turned into test failures,
// an offscreen target, and projections computed on the CPU (the independent truth the images are
// compared with).
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <string>

#include "sphxr/render/gl_context.h"
#include "sphxr/render/renderer.h"

namespace sphxr::test {

class RenderFixture : public ::testing::Test {
 public:
  static constexpr int kW = 160, kH = 120;

  void SetUp() override {
    const Status s = render::HeadlessContext::Create(true, &m_context);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_TRUE(render::OffscreenTarget::Create(kW, kH, &m_target).ok());
    render::RendererConfig config;
    config.debug = true;  // tests always run with the GL debug callback on
    config.onError = [this](const std::string& message) {
      ++m_errors;
      if (!m_expectErrors) ADD_FAILURE() << message;
    };
    const Status r = render::Renderer::Create(config, &m_renderer);
    ASSERT_TRUE(r.ok()) << r.message();
  }
  void TearDown() override {
    m_renderer.reset();
    m_target.reset();
    m_context.reset();
  }

  /// A view over the whole target.
  render::View FullView(const glm::mat4& view, const glm::mat4& projection) const {
    render::View v;
    v.view = view;
    v.projection = projection;
    v.framebuffer = m_target->Framebuffer();
    v.width = kW;
    v.height = kH;
    return v;
  }

  render::Image DrawAndRead(const render::FrameScene& scene, std::span<const render::View> views) {
    m_renderer->Draw(scene, views);
    return m_target->Read();
  }

  /// Pixel (x, y from the bottom) that a world point lands on, as floats (pixel centres at +0.5).
  static glm::vec2 Project(const glm::mat4& viewProj, glm::vec3 p, const render::View& v) {
    const glm::vec4 c = viewProj * glm::vec4(p, 1.0f);
    const glm::vec2 ndc = glm::vec2(c) / c.w;
    return {v.x + (ndc.x * 0.5f + 0.5f) * v.width, v.y + (ndc.y * 0.5f + 0.5f) * v.height};
  }

  /// World-space direction of the ray through pixel centre (x, y).
  static glm::vec3 PixelRay(const glm::mat4& viewProj, const glm::vec3& eye, float x, float y, const render::View& v) {
    const glm::vec2 ndc((x - v.x) / v.width * 2.0f - 1.0f, (y - v.y) / v.height * 2.0f - 1.0f);
    const glm::vec4 far = glm::inverse(viewProj) * glm::vec4(ndc, 1.0f, 1.0f);
    return glm::normalize(glm::vec3(far) / far.w - eye);
  }

  static glm::vec3 Rgb(const render::Image& img, int x, int y) {
    const uint8_t* p = img.At(x, y);
    return glm::vec3(p[0], p[1], p[2]) / 255.0f;
  }

  std::unique_ptr<render::HeadlessContext> m_context;
  std::unique_ptr<render::OffscreenTarget> m_target;
  std::unique_ptr<render::Renderer> m_renderer;
  int m_errors = 0;
  bool m_expectErrors = false;
};

/// Ray/box slab test: true when the ray from `o` along `d` hits the box in front of the origin.
inline bool RayHitsBox(glm::vec3 o, glm::vec3 d, glm::vec3 lo, glm::vec3 hi, float* tHit = nullptr) {
  float t0 = 0.0f, t1 = 1e30f;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d[a];
    float tn = (lo[a] - o[a]) * inv, tf = (hi[a] - o[a]) * inv;
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
    if (t0 > t1) return false;
  }
  if (tHit) *tHit = t0;
  return true;
}

/// A closed box as a triangle mesh with outward normals (indexed: 24 vertices, 36 indices).
struct BoxMesh {
  std::vector<float> positions, normals;
  std::vector<uint32_t> indices;
  BoxMesh(glm::vec3 lo, glm::vec3 hi) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        const uint32_t base = static_cast<uint32_t>(positions.size() / 3);
        for (int k = 0; k < 4; ++k) {
          glm::vec3 p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[a] = (k == 1 || k == 2) ? hi[a] : lo[a];
          p[b] = (k >= 2) ? hi[b] : lo[b];
          glm::vec3 n(0.0f);
          n[axis] = side ? 1.0f : -1.0f;
          positions.insert(positions.end(), {p.x, p.y, p.z});
          normals.insert(normals.end(), {n.x, n.y, n.z});
        }
        indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      }
    }
  }
  render::MeshView View() const {
    return {positions.data(), normals.data(), static_cast<int>(positions.size() / 3), indices.data(),
            static_cast<int>(indices.size())};
  }
};

}  // namespace sphxr::test
