#include "sphxr/app/pictures.h"

#include <stb_image.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

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
  // Encoded in memory and written by us: stbi_write_png does not check its writes, so a full disk left a
  // truncated PNG and a success. A failed write removes the partial file.
  std::string png;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<size_t>(size));
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, rgb.data(), 3 * image.width)) {
    return Status::Error(path + ": cannot encode the PNG image");
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Status::Error(path + ": cannot write the PNG file (does the directory exist and is it writable?)");
  out.write(png.data(), static_cast<std::streamsize>(png.size()));
  out.close();
  if (out.fail()) {
    std::error_code ignored;
    if (std::filesystem::is_regular_file(path, ignored)) std::filesystem::remove(path, ignored);  // (never a device)
    return Status::Error(path + ": write failed (disk full?); no partial file is left");
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
  // Across the tank's smallest extent, water absorbs most of the red light (exp(-2.4) = 9 % left); real
  // water does so over 9 m, so a tabletop tank is drawn as if its water were that deep.
  const float smallest = std::min({scene.tank.max.x - scene.tank.min.x, height, scene.tank.max.z - scene.tank.min.z});
  f.absorptionScale = std::max(1.0f, 2.4f / (render::kPureWaterAbsorption.r * std::max(smallest, 1e-3f)));
  // A tabletop tank stands on a table; a tank taller than a person stands on the ground.
  f.tableHeight = std::max({scene.tank.max.x - scene.tank.min.x, height, scene.tank.max.z - scene.tank.min.z}) <= 1.5f
                      ? 0.85f : 0.0f;
  f.particles.speedScale = std::sqrt(2.0f * 9.81f * height);  // the free-fall speed over the tank's height
  return f;
}

namespace {

struct UnitMesh {
  std::vector<float> positions, normals;
  render::MeshView View() const {
    render::MeshView v;
    v.positions = positions.data();
    v.normals = normals.data();
    v.vertexCount = static_cast<int>(positions.size() / 3);
    return v;
  }
  void Add(glm::vec3 p, glm::vec3 n) {
    positions.insert(positions.end(), {p.x, p.y, p.z});
    normals.insert(normals.end(), {n.x, n.y, n.z});
  }
};

constexpr int kSegments = 16;
constexpr float kPi = 3.14159265358979f;

/// Open cylinder of radius 1 along y from 0 to 1 (counter-clockwise seen from outside).
const UnitMesh& UnitCylinder() {
  static const UnitMesh mesh = [] {
    UnitMesh m;
    for (int i = 0; i < kSegments; ++i) {
      const float a0 = 2 * kPi * i / kSegments, a1 = 2 * kPi * (i + 1) / kSegments;
      const glm::vec3 n0(std::cos(a0), 0, -std::sin(a0)), n1(std::cos(a1), 0, -std::sin(a1));
      const glm::vec3 up(0, 1, 0);
      m.Add(n0, n0), m.Add(n1, n1), m.Add(n1 + up, n1);
      m.Add(n0, n0), m.Add(n1 + up, n1), m.Add(n0 + up, n0);
    }
    return m;
  }();
  return mesh;
}

/// Sphere of radius 1 at the origin.
const UnitMesh& UnitSphere() {
  static const UnitMesh mesh = [] {
    UnitMesh m;
    const int rings = kSegments / 2;
    auto at = [&](int i, int j) {
      const float theta = kPi * j / rings, phi = 2 * kPi * i / kSegments;
      return glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
    };
    for (int j = 0; j < rings; ++j) {
      for (int i = 0; i < kSegments; ++i) {
        const glm::vec3 a = at(i, j), b = at(i, j + 1), c = at(i + 1, j + 1), d = at(i + 1, j);
        m.Add(a, a), m.Add(b, b), m.Add(c, c);
        m.Add(a, a), m.Add(c, c), m.Add(d, d);
      }
    }
    return m;
  }();
  return mesh;
}

glm::vec3 G(sim::Vec3 v) { return {v.x, v.y, v.z}; }

}  // namespace

void AppendPaddleSolids(const PaddlePose& paddle, std::vector<render::SolidMesh>* out) {
  const interaction::Quat& q = paddle.pose.orientation;
  const glm::mat4 body = glm::translate(glm::mat4(1.0f), G(paddle.pose.position)) *
                         glm::mat4_cast(glm::quat(q.w, q.x, q.y, q.z));
  // A paddle as a paddle: its boxes are the blade (light, a hand's paddle painted, a scripted one pale
  // wood), its capsules the handle (a dark grip).
  const glm::vec3 blade = paddle.hand >= 0 ? glm::vec3(0.95f, 0.55f, 0.15f) : glm::vec3(0.85f, 0.68f, 0.45f);
  const glm::vec3 handle(0.16f, 0.16f, 0.18f);
  for (const sim::ShapePrimitive& s : paddle.shapes) {
    render::SolidMesh solid;
    solid.color = s.kind == sim::ShapePrimitive::Kind::kBox ? blade : handle;
    if (s.kind == sim::ShapePrimitive::Kind::kBox) {
      solid.model = glm::scale(glm::translate(body, G(s.a)), 2.0f * G(s.b));  // the unit cube
      out->push_back(solid);
      continue;
    }
    const glm::vec3 a = G(s.a), b = G(s.b), axis = b - a;
    const float length = glm::length(axis);
    glm::mat4 along(1.0f);
    if (length > 1e-6f) {
      const glm::vec3 dir = axis / length, y(0, 1, 0);
      const glm::vec3 c = glm::cross(y, dir);
      const float sinA = glm::length(c), cosA = glm::dot(y, dir);
      if (sinA > 1e-6f) along = glm::rotate(glm::mat4(1.0f), std::atan2(sinA, cosA), c / sinA);
      else if (cosA < 0) along = glm::rotate(glm::mat4(1.0f), kPi, glm::vec3(1, 0, 0));
      solid.mesh = UnitCylinder().View();
      solid.model = glm::translate(body, a) * along * glm::scale(glm::mat4(1.0f), glm::vec3(s.radius, length, s.radius));
      out->push_back(solid);
    }
    for (const glm::vec3& end : {a, b}) {
      solid.mesh = UnitSphere().View();
      solid.model = glm::scale(glm::translate(body, end), glm::vec3(s.radius));
      out->push_back(solid);
    }
  }
}

void AppendControllerSolids(const interaction::Pose& grip, std::vector<render::SolidMesh>* out) {
  const interaction::Quat& q = grip.orientation;
  const glm::mat4 hand = glm::translate(glm::mat4(1.0f), G(grip.position)) * glm::mat4_cast(glm::quat(q.w, q.x, q.y, q.z));
  const glm::vec3 body(0.10f, 0.10f, 0.11f), ring(0.22f, 0.23f, 0.26f);
  // The grip: a cylinder along the grip space's z axis (OpenXR: -z points out of the hand's front),
  // 4 cm across, from 5 cm behind the palm to 6 cm in front of it, rounded at both ends.
  const glm::mat4 alongZ = glm::rotate(glm::mat4(1.0f), kPi / 2, glm::vec3(1, 0, 0));  // the unit cylinder's y to z
  render::SolidMesh grip_;
  grip_.color = body;
  grip_.mesh = UnitCylinder().View();
  grip_.model = glm::translate(hand, glm::vec3(0, 0, -0.06f)) * alongZ * glm::scale(glm::mat4(1.0f), glm::vec3(0.02f, 0.11f, 0.02f));
  out->push_back(grip_);
  for (const float z : {-0.06f, 0.05f}) {
    render::SolidMesh end;
    end.color = body;
    end.mesh = UnitSphere().View();
    end.model = glm::scale(glm::translate(hand, glm::vec3(0, 0, z)), glm::vec3(0.02f));
    out->push_back(end);
  }
  // The tracking ring in front of the hand: a flat disc 9 cm across, tilted up.
  render::SolidMesh disc;
  disc.color = ring;
  disc.mesh = UnitCylinder().View();
  disc.model = glm::translate(hand, glm::vec3(0, 0.02f, -0.08f)) * glm::rotate(glm::mat4(1.0f), 0.6f, glm::vec3(1, 0, 0)) *
               glm::scale(glm::mat4(1.0f), glm::vec3(0.045f, 0.012f, 0.045f));
  out->push_back(disc);
}

render::FrameScene MakeFrameScene(const SimSnapshot& snapshot, render::RenderMode mode, render::ParticleColor color,
                                  const render::InteropMesh* deviceSurface) {
  render::FrameScene f = MakeFrameScene(snapshot.setup, snapshot.fluid, mode, color);
  if (mode == render::RenderMode::kWater && snapshot.surfaceOnDevice) {
    f.deviceSurface = deviceSurface;  // null (nothing written yet): the particles are drawn as water
  } else if (mode == render::RenderMode::kWater && snapshot.surface.VertexCount() > 0) {
    f.surface.positions = snapshot.surface.positions.data();
    f.surface.normals = snapshot.surface.normals.data();
    f.surface.vertexCount = static_cast<int>(snapshot.surface.VertexCount());
  }
  for (const PaddlePose& p : snapshot.paddles) AppendPaddleSolids(p, &f.solids);
  if (mode == render::RenderMode::kWater && snapshot.diffuse.count > 0) {  // spray, foam and bubbles
    f.diffuse.position = snapshot.diffuse.position.data();
    f.diffuse.velocity = snapshot.diffuse.velocity.data();
    f.diffuse.count = snapshot.diffuse.count;
    f.diffuse.radius = 0.4f * snapshot.setup.params.spacing;
  }
  return f;
}

Status OfflinePictures::Create(int width, int height, std::unique_ptr<OfflinePictures>* out, bool glDebug,
                               render::RenderQuality quality) {
  out->reset();
  std::unique_ptr<OfflinePictures> p(new OfflinePictures());
  p->m_width = width;
  p->m_height = height;
  render::RendererConfig config;
  config.debug = config.debug || glDebug;
  config.quality = quality;
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
