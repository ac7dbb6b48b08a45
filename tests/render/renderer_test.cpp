// The renderer under Mesa llvmpipe through EGL, with the GL debug callback on (any GL error fails the
// test). Every image is compared with truth computed here on the CPU: pixel rays and projections from
// the same matrices, ray/box intersections, Beer-Lambert transmission along the measured path.
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <array>
#include <vector>

#include "render_support.h"
#include "sphxr/render/interop.h"

namespace sphxr::test {
namespace {

constexpr float kFov = 0.8f;

glm::mat4 Perspective(float aspect) { return glm::perspective(kFov, aspect, 0.05f, 50.0f); }

render::FrameScene EmptyScene() {
  render::FrameScene s;
  s.drawFloor = false;
  s.drawTank = false;
  return s;
}

float MaxDiff(glm::vec3 a, glm::vec3 b) {
  const glm::vec3 d = glm::abs(a - b);
  return std::max({d.x, d.y, d.z});
}

using RendererTest = RenderFixture;

TEST_F(RendererTest, SkyMatchesItsFormulaInEveryPixel) {
  const glm::vec3 eye(0.0f, 0.5f, 2.0f);
  const glm::mat4 view = glm::lookAt(eye, glm::vec3(0.0f, 0.9f, 0.0f), glm::vec3(0, 1, 0));
  const render::View v = FullView(view, Perspective(float(kW) / kH));
  const render::Image img = DrawAndRead(EmptyScene(), std::span(&v, 1));
  const glm::mat4 vp = v.projection * v.view;
  const glm::vec3 sun = glm::normalize(m_renderer->Config().sunDirection);
  float worst = 0.0f;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const glm::vec3 expected = render::SkyColor(PixelRay(vp, eye, x + 0.5f, y + 0.5f, v), sun);
      worst = std::max(worst, MaxDiff(Rgb(img, x, y), expected));
    }
  }
  EXPECT_LE(worst, 2.5f / 255.0f) << "largest difference from the sky formula, in 8-bit steps: " << worst * 255;
  // The gradient is there: the top row is bluer and darker than the horizon row.
  const glm::vec3 top = Rgb(img, kW / 2, kH - 1), low = Rgb(img, kW / 2, 0);
  EXPECT_LT(top.r, low.r - 0.05f);
}

TEST_F(RendererTest, BoxCoversExactlyThePixelsWhoseRaysHitIt) {
  const glm::vec3 lo(-0.3f, 0.2f, -0.2f), hi(0.3f, 0.7f, 0.2f);
  render::FrameScene scene = EmptyScene();
  scene.obstacles.push_back(sim::Aabb{{lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}});
  const glm::vec3 eye(0.8f, 1.2f, 2.0f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0, 0.45f, 0), glm::vec3(0, 1, 0)),
                                  Perspective(float(kW) / kH));
  const render::Image img = DrawAndRead(scene, std::span(&v, 1));
  const glm::mat4 vp = v.projection * v.view;
  const glm::vec3 sun = glm::normalize(m_renderer->Config().sunDirection);

  std::vector<int> truth(kW * kH), drawn(kW * kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const glm::vec3 ray = PixelRay(vp, eye, x + 0.5f, y + 0.5f, v);
      truth[y * kW + x] = RayHitsBox(eye, ray, lo, hi);
      drawn[y * kW + x] = MaxDiff(Rgb(img, x, y), render::SkyColor(ray, sun)) > 3.0f / 255.0f;
    }
  }
  int covered = 0, wrong = 0;
  for (int y = 1; y < kH - 1; ++y) {
    for (int x = 1; x < kW - 1; ++x) {
      const int t = truth[y * kW + x];
      covered += t;
      bool edge = false;  // a pixel whose neighbours disagree with it lies on the silhouette: either is right
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) edge |= truth[(y + dy) * kW + x + dx] != t;
      }
      if (!edge && drawn[y * kW + x] != t) ++wrong;
    }
  }
  EXPECT_GT(covered, 1000) << "the box should fill a good part of the image";
  EXPECT_EQ(wrong, 0) << "pixels away from the silhouette that disagree with the ray/box test";

  // Lighting of the top face (normal +y) at its projected centre: base * (0.45 sky(n) + 0.65 n.sun).
  const glm::vec2 p = Project(vp, glm::vec3(0.0f, hi.y, 0.0f), v);
  const glm::vec3 base(0.55f, 0.52f, 0.50f);
  const glm::vec3 n(0, 1, 0);
  const glm::vec3 expected = base * (0.45f * render::SkyColor(n, sun) + 0.65f * std::max(glm::dot(n, sun), 0.0f));
  EXPECT_LE(MaxDiff(Rgb(img, int(p.x), int(p.y)), glm::min(expected, glm::vec3(1.0f))), 2.5f / 255.0f);
}

/// Centroid and count of pixels that differ from the sky inside a viewport.
struct Blob {
  glm::vec2 centroid{0.0f};
  int count = 0;
};
Blob FindBlob(const render::Image& img, const render::View& v, const glm::vec3& eye, const glm::vec3& sun) {
  const glm::mat4 vp = v.projection * v.view;
  Blob b;
  for (int y = v.y; y < v.y + v.height; ++y) {
    for (int x = v.x; x < v.x + v.width; ++x) {
      const glm::vec3 ray = RenderFixture::PixelRay(vp, eye, x + 0.5f, y + 0.5f, v);
      const glm::vec3 c = glm::vec3(img.At(x, y)[0], img.At(x, y)[1], img.At(x, y)[2]) / 255.0f;
      if (MaxDiff(c, render::SkyColor(ray, sun)) > 3.0f / 255.0f) {
        b.centroid += glm::vec2(x + 0.5f, y + 0.5f);
        ++b.count;
      }
    }
  }
  if (b.count) b.centroid /= float(b.count);
  return b;
}

TEST_F(RendererTest, ParticleAppearsAtItsProjectedPixelWithItsProjectedSize) {
  const sim::Vec4 position{0.1f, 0.6f, 0.0f, 0.0f};
  const sim::Vec4 velocity{0.0f, 0.0f, 0.0f, 0.0f};
  render::FrameScene scene = EmptyScene();
  scene.mode = render::RenderMode::kParticles;
  scene.particles.position = &position;
  scene.particles.velocity = &velocity;
  scene.particles.count = 1;
  scene.particles.radius = 0.05f;
  const glm::vec3 eye(0.0f, 0.5f, 2.0f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0, 0.5f, 0), glm::vec3(0, 1, 0)),
                                  Perspective(float(kW) / kH));
  const render::Image img = DrawAndRead(scene, std::span(&v, 1));
  const glm::mat4 vp = v.projection * v.view;
  const glm::vec2 expected = Project(vp, glm::vec3(position.x, position.y, position.z), v);
  const Blob blob = FindBlob(img, v, eye, glm::normalize(m_renderer->Config().sunDirection));
  ASSERT_GT(blob.count, 0) << "the particle is not in the image";
  EXPECT_NEAR(blob.centroid.x, expected.x, 0.75f);
  EXPECT_NEAR(blob.centroid.y, expected.y, 0.75f);
  // A sphere of radius r at eye depth z covers a disc of radius r * f / z pixels (f = P[1][1] h / 2).
  const float depth = 2.0f;
  const float radiusPx = 0.05f * v.projection[1][1] * 0.5f * kH / depth;
  const float area = 3.14159265f * radiusPx * radiusPx;
  EXPECT_NEAR(blob.count, area, 0.15f * area);
  // Speed 0 maps to the bottom of the colour map (blue).
  const glm::vec3 c = Rgb(img, int(expected.x), int(expected.y));
  EXPECT_GT(c.b, c.r + 0.2f);
  EXPECT_GT(c.b, c.g + 0.1f);
}

TEST_F(RendererTest, TwoEyeViewsDifferByTheExpectedParallax) {
  // One target, two viewports side by side, as a headset's double-wide swapchain would be.
  const sim::Vec4 position{0.0f, 0.5f, -1.0f, 0.0f};
  render::FrameScene scene = EmptyScene();
  scene.mode = render::RenderMode::kParticles;
  scene.particles.position = &position;
  scene.particles.count = 1;
  scene.particles.radius = 0.02f;
  const float ipd = 0.064f;
  const glm::mat4 proj = Perspective(float(kW / 2) / kH);
  std::array<render::View, 2> views;
  std::array<glm::vec3, 2> eyes;
  for (int e = 0; e < 2; ++e) {
    eyes[e] = glm::vec3((e == 0 ? -0.5f : 0.5f) * ipd, 0.5f, 0.0f);
    views[e] = FullView(glm::lookAt(eyes[e], eyes[e] + glm::vec3(0, 0, -1), glm::vec3(0, 1, 0)), proj);
    views[e].x = e * kW / 2;
    views[e].width = kW / 2;
  }
  const render::Image img = DrawAndRead(scene, views);
  const glm::vec3 sun = glm::normalize(m_renderer->Config().sunDirection);
  const Blob left = FindBlob(img, views[0], eyes[0], sun), right = FindBlob(img, views[1], eyes[1], sun);
  ASSERT_GT(left.count, 0);
  ASSERT_GT(right.count, 0);
  // Disparity of a point at depth d for eyes ipd apart: f_px * ipd / d, with f_px = P[0][0] w / 2.
  const float fPx = proj[0][0] * 0.5f * (kW / 2);
  const float expected = fPx * ipd / 1.0f;
  const float measured = (left.centroid.x - views[0].x) - (right.centroid.x - views[1].x);
  EXPECT_GT(expected, 5.0f) << "the test should see a parallax of several pixels";
  EXPECT_NEAR(measured, expected, 0.5f);
  EXPECT_NEAR(left.centroid.y, right.centroid.y, 0.25f);
}

TEST_F(RendererTest, WaterFromParticlesIsWaterColouredWhereTheFluidIsAndNowhereElse) {
  const glm::vec3 lo(-0.2f, 0.2f, -0.1f), hi(0.2f, 0.5f, 0.1f);
  const float spacing = 0.02f;
  std::vector<sim::Vec4> positions;
  for (float x = lo.x + 0.5f * spacing; x < hi.x; x += spacing) {
    for (float y = lo.y + 0.5f * spacing; y < hi.y; y += spacing) {
      for (float z = lo.z + 0.5f * spacing; z < hi.z; z += spacing) positions.push_back({x, y, z, 0});
    }
  }
  render::FrameScene scene = EmptyScene();
  scene.mode = render::RenderMode::kWater;  // no surface mesh: the particles are drawn as water
  scene.particles.position = positions.data();
  scene.particles.count = static_cast<int>(positions.size());
  scene.particles.radius = 0.6f * spacing;
  const glm::vec3 eye(0.3f, 0.9f, 1.4f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0, 0.35f, 0), glm::vec3(0, 1, 0)),
                                  Perspective(float(kW) / kH));
  const render::Image img = DrawAndRead(scene, std::span(&v, 1));
  const glm::mat4 vp = v.projection * v.view;
  const glm::vec3 sun = glm::normalize(m_renderer->Config().sunDirection);
  // Truth: the block of particles, grown by a radius (the spheres' outer extent).
  const glm::vec3 grow(0.6f * spacing - 0.5f * spacing);
  int inside = 0, insideWater = 0, outside = 0, outsideNotSky = 0;
  for (int y = 2; y < kH - 2; ++y) {
    for (int x = 2; x < kW - 2; ++x) {
      const glm::vec3 ray = PixelRay(vp, eye, x + 0.5f, y + 0.5f, v);
      // Away from the silhouette: all rays within 2 pixels agree.
      int hits = 0;
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          hits += RayHitsBox(eye, PixelRay(vp, eye, x + dx + 0.5f, y + dy + 0.5f, v), lo - grow, hi + grow);
        }
      }
      const glm::vec3 c = Rgb(img, x, y);
      if (hits == 25) {
        ++inside;
        // Water: blue-green, with the red absorbed, and visibly not the sky behind it.
        insideWater += (c.b > c.r + 0.08f && c.g > c.r && MaxDiff(c, render::SkyColor(ray, sun)) > 0.05f);
      } else if (hits == 0) {
        ++outside;
        outsideNotSky += MaxDiff(c, render::SkyColor(ray, sun)) > 3.0f / 255.0f;
      }
    }
  }
  EXPECT_GT(inside, 800);
  EXPECT_GE(insideWater, inside * 98 / 100) << insideWater << " of " << inside << " pixels inside are water-coloured";
  EXPECT_EQ(outsideNotSky, 0) << "of " << outside << " pixels outside the fluid";
}

TEST_F(RendererTest, WaterMeshTransmitsByBeerLambertOverItsThickness) {
  // Two water slabs seen nearly head-on against the sky: 5 cm thick on the left, 50 cm on the right.
  const float thin = 0.05f, thick = 0.5f;
  for (const float depth : {thin, thick}) {
    const glm::vec3 lo(-0.3f, 0.2f, -depth), hi(0.3f, 0.8f, 0.0f);
    const BoxMesh mesh(lo, hi);
    render::FrameScene scene = EmptyScene();
    scene.surface = mesh.View();
    const glm::vec3 eye(0.0f, 0.5f, 2.0f);
    const render::View v = FullView(glm::lookAt(eye, glm::vec3(0, 0.5f, 0), glm::vec3(0, 1, 0)),
                                    Perspective(float(kW) / kH));
    const render::Image img = DrawAndRead(scene, std::span(&v, 1));
    const glm::mat4 vp = v.projection * v.view;
    const render::RendererConfig& cfg = m_renderer->Config();
    const glm::vec3 sun = glm::normalize(cfg.sunDirection);
    // Several pixels over the front face, away from its edges: the expected colour from the optics,
    // with the path length measured by the ray/box test (entry and exit).
    int checked = 0;
    for (int y = kH / 2 - 10; y <= kH / 2 + 10; y += 5) {
      for (int x = kW / 2 - 20; x <= kW / 2 + 20; x += 10) {
        const glm::vec3 ray = PixelRay(vp, eye, x + 0.5f, y + 0.5f, v);
        float tIn = 0.0f, tOut = 0.0f;
        ASSERT_TRUE(RayHitsBox(eye, ray, lo, hi, &tIn));
        const glm::vec3 far = eye + ray * 100.0f;
        ASSERT_TRUE(RayHitsBox(far, -ray, lo, hi, &tOut));
        const float path = (100.0f - tOut) - tIn;
        const glm::vec3 n(0, 0, 1);
        const float cosT = glm::dot(n, -ray);
        const float fresnel = 0.02f + 0.98f * std::pow(1.0f - cosT, 5.0f);
        const glm::vec3 r = glm::reflect(ray, n);
        const float spec = 3.0f * std::pow(std::max(glm::dot(r, sun), 0.0f), 300.0f);
        const glm::vec3 transmission = glm::exp(-cfg.waterAbsorption * scene.absorptionScale * path);
        const glm::vec3 body = cfg.waterColor * (glm::vec3(1.0f) - transmission) * (0.55f + 0.45f * sun.y);
        const glm::vec3 expected = fresnel * render::SkyColor(r, sun) + (1.0f - fresnel) * body + spec +
                                   render::SkyColor(ray, sun) * (1.0f - fresnel) * transmission;
        EXPECT_LE(MaxDiff(Rgb(img, x, y), glm::min(expected, glm::vec3(1.0f))), 3.0f / 255.0f)
            << "slab " << depth << " m, pixel " << x << "," << y << " path " << path;
        ++checked;
      }
    }
    EXPECT_EQ(checked, 25);
    if (depth == thick) {
      // Red is absorbed first: behind 50 cm of water the red channel is far below the sky's.
      const glm::vec3 c = Rgb(img, kW / 2, kH / 2);
      EXPECT_LT(c.r, 0.5f * render::SkyColor(PixelRay(vp, eye, kW / 2 + 0.5f, kH / 2 + 0.5f, v), sun).r);
    }
  }
}

TEST_F(RendererTest, DebugCallbackCatchesADeliberateGlError) {
  m_expectErrors = true;
  ASSERT_EQ(m_errors, 0);
  glBindBuffer(GL_ARRAY_BUFFER, 0x7fff1234u);  // not a name from glCreateBuffers: GL_INVALID_OPERATION in core
  EXPECT_EQ(m_errors, 1) << "the synchronous debug callback did not report the error";
  EXPECT_EQ(m_renderer->ErrorCount(), 1);
}

TEST_F(RendererTest, FullSceneRendersWithoutGlErrors) {
  // Floor, tank edges, an obstacle, a paddle (unit cube and an indexed mesh), particles as water and
  // as coloured sprites in every colour mode, two views: the debug callback fails the test on any error.
  std::vector<sim::Vec4> positions, velocities;
  std::vector<float> density;
  std::vector<int32_t> idle;
  for (int i = 0; i < 200; ++i) {
    positions.push_back({0.1f + 0.002f * i, 0.05f + 0.001f * i, 0.1f, 0});
    velocities.push_back({0.01f * i, 0, 0, 0});
    density.push_back(1000.0f + i);
    idle.push_back(i % 3 - 1);
  }
  const BoxMesh paddle(glm::vec3(-0.5f), glm::vec3(0.5f));
  render::FrameScene scene;
  scene.tank = sim::Aabb{{0, 0, 0}, {0.6f, 0.4f, 0.3f}};
  scene.obstacles.push_back(sim::Aabb{{0.4f, 0, 0.1f}, {0.5f, 0.1f, 0.2f}});
  scene.solids.push_back(render::SolidMesh{});
  scene.solids.push_back(render::SolidMesh{paddle.View(), glm::translate(glm::mat4(1.0f), glm::vec3(0.3f, 0.3f, 0.1f)),
                                           glm::vec3(0.2f, 0.8f, 0.3f)});
  scene.particles = {positions.data(), velocities.data(), density.data(), idle.data(), 200, 0.01f};
  const render::Camera camera = render::FrameBox(scene.tank, float(kW) / kH);
  std::array<render::View, 2> views = {FullView(camera.View(), camera.Projection(float(kW) / kH)),
                                       FullView(camera.View(), camera.Projection(float(kW) / kH))};
  views[1].x = kW / 2;
  views[1].width = kW / 2;
  for (const auto mode : {render::RenderMode::kWater, render::RenderMode::kParticles}) {
    for (const auto color : {render::ParticleColor::kSpeed, render::ParticleColor::kDensityError,
                             render::ParticleColor::kActivity}) {
      scene.mode = mode;
      scene.particleColor = color;
      DrawAndRead(scene, views);
    }
  }
  const BoxMesh water(glm::vec3(0.05f, 0.0f, 0.05f), glm::vec3(0.3f, 0.1f, 0.25f));
  scene.surface = water.View();
  scene.mode = render::RenderMode::kWater;
  DrawAndRead(scene, views);
  EXPECT_EQ(m_renderer->ErrorCount(), 0);
}

TEST(RendererEnvironmentTest, RefusesAContextWithoutOpenGl45InOneLine) {
  // An OpenGL ES 3 context (what a GLES-only driver offers): Create must refuse it with one clear line.
  EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  ASSERT_NE(display, EGL_NO_DISPLAY);
  ASSERT_TRUE(eglInitialize(display, nullptr, nullptr));
  const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_NONE};
  EGLConfig config;
  EGLint count = 0;
  ASSERT_TRUE(eglChooseConfig(display, configAttribs, &config, 1, &count) && count == 1);
  ASSERT_TRUE(eglBindAPI(EGL_OPENGL_ES_API));
  const EGLint contextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttribs);
  ASSERT_NE(context, EGL_NO_CONTEXT);
  ASSERT_TRUE(eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context));
  std::unique_ptr<render::Renderer> renderer;
  const Status s = render::Renderer::Create(render::RendererConfig{}, &renderer);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(renderer, nullptr);
  EXPECT_NE(s.message().find("needs OpenGL 4.5"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line";
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, context);
  eglBindAPI(EGL_OPENGL_API);
}

}  // namespace
}  // namespace sphxr::test

namespace sphxr::test {
namespace {

TEST_F(RendererTest, MeshInGlBuffersDrawsLikeTheSameMeshFromTheHost) {
  // The interop path (buffers the GPU backend writes in place) against the host upload path: the
  // renderer must draw the same pixels. Here the buffers are filled by Upload (no GPU on this machine);
  // with CUDA, Map/Unmap fill the same buffers.
  const glm::vec3 lo(-0.3f, 0.2f, -0.2f), hi(0.3f, 0.8f, 0.0f);
  const BoxMesh box(lo, hi);
  std::vector<float> positions, normals;  // de-indexed: the interop mesh is plain triangles
  for (uint32_t i : box.indices) {
    positions.insert(positions.end(), {box.positions[3 * i], box.positions[3 * i + 1], box.positions[3 * i + 2]});
    normals.insert(normals.end(), {box.normals[3 * i], box.normals[3 * i + 1], box.normals[3 * i + 2]});
  }
  const glm::vec3 eye(0.4f, 0.9f, 2.0f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0, 0.5f, 0), glm::vec3(0, 1, 0)), Perspective(float(kW) / kH));
  render::FrameScene scene = EmptyScene();
  scene.surface = box.View();
  const render::Image host = DrawAndRead(scene, std::span(&v, 1));

  std::unique_ptr<render::InteropMesh> device;
  ASSERT_TRUE(render::InteropMesh::Create(64, &device).ok());
  ASSERT_TRUE(device->Upload(positions.data(), normals.data(), static_cast<int>(positions.size() / 3)).ok());
  scene.surface = render::MeshView{};
  scene.deviceSurface = device.get();
  const render::Image viaBuffers = DrawAndRead(scene, std::span(&v, 1));
  int differing = 0;
  for (size_t i = 0; i < host.rgba.size(); ++i) differing += host.rgba[i] != viaBuffers.rgba[i];
  EXPECT_EQ(differing, 0);
  int water = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) water += Rgb(host, x, y).b > Rgb(host, x, y).r + 0.1f;
  }
  EXPECT_GT(water, 1000) << "the slab should be in the picture";
#if !SPHXR_HAVE_CUDA
  render::InteropMesh::DevicePointers pointers;
  const Status s = device->Map(&pointers);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no CUDA backend"), std::string::npos) << s.message();
#endif
  m_renderer.reset();  // before the mesh's buffers go
}

TEST_F(RendererTest, MeshInGlBuffersIsDrawnWithTheCountOfItsIndirectCommand) {
  // The mesh written in place is drawn by glDrawArraysIndirect: its vertex count is the one in the draw
  // command buffer (which CUDA fills on the device), not one the host knows. Upload fills the command
  // with the whole mesh; the command is then rewritten here as the device would: the first 18 vertices
  // draw what a host mesh of those 18 vertices draws, and 0 draws no water.
  const BoxMesh box(glm::vec3(-0.3f, 0.2f, -0.2f), glm::vec3(0.3f, 0.8f, 0.0f));
  std::vector<float> positions, normals;
  for (uint32_t i : box.indices) {
    positions.insert(positions.end(), {box.positions[3 * i], box.positions[3 * i + 1], box.positions[3 * i + 2]});
    normals.insert(normals.end(), {box.normals[3 * i], box.normals[3 * i + 1], box.normals[3 * i + 2]});
  }
  ASSERT_GT(positions.size() / 3, 18u);
  const glm::vec3 eye(0.4f, 0.9f, 2.0f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0, 0.5f, 0), glm::vec3(0, 1, 0)), Perspective(float(kW) / kH));
  auto differing = [](const render::Image& a, const render::Image& b) {
    int n = 0;
    for (size_t i = 0; i < a.rgba.size(); ++i) n += a.rgba[i] != b.rgba[i];
    return n;
  };
  render::FrameScene scene = EmptyScene();
  render::MeshView part;
  part.positions = positions.data();
  part.normals = normals.data();
  part.vertexCount = 18;
  scene.surface = part;
  const render::Image hostPart = DrawAndRead(scene, std::span(&v, 1));
  scene.surface.vertexCount = static_cast<int>(positions.size() / 3);
  const render::Image hostWhole = DrawAndRead(scene, std::span(&v, 1));
  ASSERT_GT(differing(hostPart, hostWhole), 100) << "the two counts must draw different pictures";

  std::unique_ptr<render::InteropMesh> device;
  ASSERT_TRUE(render::InteropMesh::Create(64, &device).ok());
  EXPECT_FALSE(device->Written());
  ASSERT_TRUE(device->Upload(positions.data(), normals.data(), static_cast<int>(positions.size() / 3)).ok());
  EXPECT_TRUE(device->Written());
  uint32_t command[4] = {};
  glGetNamedBufferSubData(device->DrawCommandBuffer(), 0, sizeof(command), command);
  EXPECT_EQ(command[0], positions.size() / 3);
  EXPECT_EQ(command[1], 1u);
  scene.surface = render::MeshView{};
  scene.deviceSurface = device.get();
  EXPECT_EQ(differing(DrawAndRead(scene, std::span(&v, 1)), hostWhole), 0);
  command[0] = 18;
  glNamedBufferSubData(device->DrawCommandBuffer(), 0, sizeof(command), command);
  EXPECT_EQ(differing(DrawAndRead(scene, std::span(&v, 1)), hostPart), 0);
  command[0] = 0;
  glNamedBufferSubData(device->DrawCommandBuffer(), 0, sizeof(command), command);
  const render::Image none = DrawAndRead(scene, std::span(&v, 1));
  EXPECT_EQ(differing(none, DrawAndRead(EmptyScene(), std::span(&v, 1))), 0) << "0 vertices: no water";
  m_renderer.reset();  // before the mesh's buffers go
}

}  // namespace
}  // namespace sphxr::test

namespace sphxr::test {
namespace {

TEST(RendererDeathTest, GlErrorWithoutAHandlerAbortsNamingTheError) {
  // What a debug build does (RendererConfig::debug on, no handler): the synchronous callback logs the
  // error and aborts at the call that made it.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(
      {
        std::unique_ptr<render::HeadlessContext> context;
        if (!render::HeadlessContext::Create(true, &context).ok()) std::abort();
        render::RendererConfig config;
        config.debug = true;
        std::unique_ptr<render::Renderer> renderer;
        if (!render::Renderer::Create(config, &renderer).ok()) std::abort();
        glBindBuffer(GL_ARRAY_BUFFER, 0x7fff1234u);
        std::fprintf(stderr, "no abort\n");
        std::exit(0);
      },
      "GL error \\(id [0-9]+\\): .*");
}

}  // namespace
}  // namespace sphxr::test

namespace sphxr::test {
namespace {

TEST_F(RendererTest, DrawCallsOfOneFrameShareItsUploadAndANewFrameUploadsAgain) {
  // A headset draws its eyes one call each: the calls that carry the same FrameScene::frameKey reuse
  // the first call's upload (here: the second call's scene has no water, and the water is still drawn);
  // the next frame's key uploads again.
  const BoxMesh water(glm::vec3(-0.3f, 0.2f, -0.2f), glm::vec3(0.3f, 0.7f, 0.1f));
  render::FrameScene scene = EmptyScene();
  scene.surface = water.View();
  scene.frameKey = 7;
  const render::View v = FullView(glm::lookAt(glm::vec3(0.0f, 0.5f, 2.0f), glm::vec3(0, 0.45f, 0), glm::vec3(0, 1, 0)),
                                  Perspective(float(kW) / kH));
  const render::Image first = DrawAndRead(scene, std::span(&v, 1));
  render::FrameScene dry = EmptyScene();
  dry.frameKey = 7;
  const render::Image sameFrame = DrawAndRead(dry, std::span(&v, 1));
  dry.frameKey = 8;
  const render::Image nextFrame = DrawAndRead(dry, std::span(&v, 1));
  int differsSame = 0, differsNext = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      differsSame += MaxDiff(Rgb(first, x, y), Rgb(sameFrame, x, y)) > 0.0f;
      differsNext += MaxDiff(Rgb(first, x, y), Rgb(nextFrame, x, y)) > 3.0f / 255.0f;
    }
  }
  EXPECT_EQ(differsSame, 0) << "the second call of frame 7 did not draw frame 7's upload";
  EXPECT_GT(differsNext, 1000) << "frame 8 still shows frame 7's water";
}

}  // namespace
}  // namespace sphxr::test
