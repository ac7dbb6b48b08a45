#include "sphxr/app/pictures.h"

#include <stb_image.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "sphxr/common/log.h"

namespace sphxr::app {

Status WritePng(const std::string& path, const render::Image& image) {
  if (image.width <= 0 || image.height <= 0) return Status::Error(path + ": empty image");
  std::vector<uint8_t> rgb(3 * static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) {
    const uint8_t* src = image.At(0, image.height - 1 - y);
    uint8_t* dst = &rgb[3 * static_cast<size_t>(y) * image.width];
    for (int x = 0; x < image.width; ++x) {
      dst[3 * x + 0] = src[4 * x + 0];
      dst[3 * x + 1] = src[4 * x + 1];
      dst[3 * x + 2] = src[4 * x + 2];
    }
  }
  if (!stbi_write_png(path.c_str(), image.width, image.height, 3, rgb.data(), 3 * image.width)) {
    return Status::Error(path + ": cannot write the PNG file (does the directory exist and is it writable?)");
  }
  return Status::Ok();
}

Status ReadPng(const std::string& path, render::Image* out) {
  int w = 0, h = 0, n = 0;
  stbi_uc* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  if (!data) return Status::Error(path + ": cannot read as PNG: " + stbi_failure_reason());
  out->width = w;
  out->height = h;
  out->rgba.assign(data, data + 4 * static_cast<size_t>(w) * h);
  stbi_image_free(data);
  out->FlipRows();
  return Status::Ok();
}

render::FrameScene MakeFrameScene(const sim::SceneSetup& scene, const sim::HostFluid& fluid, render::RenderMode mode,
                                  render::ParticleColor color) {
  render::FrameScene f;
  f.mode = mode;
  f.particleColor = color;
  f.tank = scene.tank;
  f.obstacles = scene.obstacles;
  f.particles.position = fluid.position.data();
  f.particles.velocity = fluid.velocity.data();
  f.particles.density = fluid.density.data();
  f.particles.idle = fluid.idle.data();
  f.particles.count = static_cast<int>(fluid.size());
  // Spheres a little larger than half the spacing overlap into a continuous body of water.
  f.particles.radius = (mode == render::RenderMode::kWater ? 0.75f : 0.5f) * scene.params.spacing;
  f.particles.restDensity = scene.params.restDensity;
  const float height = std::max(scene.tank.max.y - scene.tank.min.y, 1e-3f);
  // Across the tank's smallest extent, water absorbs most of the red light (exp(-0.6 * 4) = 9 % left).
  const float smallest = std::min({scene.tank.max.x - scene.tank.min.x, height, scene.tank.max.z - scene.tank.min.z});
  f.absorptionScale = std::max(1.0f, 0.6f / std::max(smallest, 1e-3f));
  f.particles.speedScale = std::sqrt(2.0f * 9.81f * height);  // the free-fall speed over the tank's height
  return f;
}

Status OfflinePictures::Create(int width, int height, std::unique_ptr<OfflinePictures>* out, bool glDebug) {
  out->reset();
  std::unique_ptr<OfflinePictures> p(new OfflinePictures());
  p->m_width = width;
  p->m_height = height;
  render::RendererConfig config;
  config.debug = config.debug || glDebug;
  if (Status s = render::HeadlessContext::Create(config.debug, &p->m_context); !s) return s;
  if (Status s = render::OffscreenTarget::Create(width, height, &p->m_target); !s) return s;
  if (Status s = render::Renderer::Create(config, &p->m_renderer); !s) return s;
  SPHXR_LOG_INFO("pictures: %dx%d through EGL (%s)", width, height, render::GlDescription());
  *out = std::move(p);
  return Status::Ok();
}

Status OfflinePictures::Write(const render::FrameScene& frame, const std::string& path) {
  const float aspect = static_cast<float>(m_width) / static_cast<float>(m_height);
  const render::Camera camera = render::FrameBox(frame.tank, aspect);
  render::View view;
  view.view = camera.View();
  view.projection = camera.Projection(aspect);
  view.framebuffer = m_target->Framebuffer();
  view.width = m_width;
  view.height = m_height;
  m_renderer->Draw(frame, std::span(&view, 1));
  return WritePng(path, m_target->Read());
}

std::string FindOnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return {};
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::filesystem::path candidate = std::filesystem::path(dir) / program;
    if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return {};
}

}  // namespace sphxr::app
