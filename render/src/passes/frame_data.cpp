#include "passes/frame_data.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <glm/gtc/matrix_transform.hpp>

#include "sphxr/render/interop.h"

namespace sphxr::render {
namespace {

/// Unit cube centred at the origin, counter-clockwise seen from outside; faces in the order x+, x-, y+,
/// y-, z+, z- (six vertices each: the panes of an open tank skip y+, vertices 12-17).
std::vector<float> CubeTriangles() {
  std::vector<float> v;
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const float sign = (f % 2 == 0) ? 1.0f : -1.0f;
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

glm::mat4 BoxModel(glm::vec3 lo, glm::vec3 hi) {
  return glm::scale(glm::translate(glm::mat4(1.0f), 0.5f * (lo + hi)), hi - lo);
}

glm::vec3 V(sim::Vec3 p) { return {p.x, p.y, p.z}; }

}  // namespace

FrameData::FrameData() {
  const std::vector<float> c = CubeTriangles();
  cube.Upload(c.data(), c.size() * sizeof(float));
  cubeVertices = static_cast<int>(c.size() / 6);
  const float q[] = {-0.5f, 0, -0.5f, 0, 1, 0, 0.5f, 0, 0.5f, 0, 1, 0, 0.5f, 0, -0.5f, 0, 1, 0,
                     -0.5f, 0, -0.5f, 0, 1, 0, -0.5f, 0, 0.5f, 0, 1, 0, 0.5f, 0, 0.5f, 0, 1, 0};
  quad.Upload(q, sizeof(q));
  uniforms.Upload(nullptr, sizeof(ViewUniforms));

  glCreateVertexArrays(1, &emptyVao);
  // Solids: interleaved position + normal in one binding (the buffer is chosen per draw).
  glCreateVertexArrays(1, &solidVao);
  glEnableVertexArrayAttrib(solidVao, 0);
  glEnableVertexArrayAttrib(solidVao, 1);
  glVertexArrayAttribFormat(solidVao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribFormat(solidVao, 1, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float));
  glVertexArrayAttribBinding(solidVao, 0, 0);
  glVertexArrayAttribBinding(solidVao, 1, 0);
  // Water mesh and particles: buffers are (re)bound at upload.
  glCreateVertexArrays(1, &meshVao);
  glEnableVertexArrayAttrib(meshVao, 0);
  glEnableVertexArrayAttrib(meshVao, 1);
  glVertexArrayAttribFormat(meshVao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribFormat(meshVao, 1, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(meshVao, 0, 0);
  glVertexArrayAttribBinding(meshVao, 1, 1);
  glCreateVertexArrays(1, &spriteVao);
  glEnableVertexArrayAttrib(spriteVao, 0);
  glVertexArrayAttribFormat(spriteVao, 0, 4, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(spriteVao, 0, 0);
}

FrameData::~FrameData() {
  for (GLuint v : {emptyVao, solidVao, meshVao, spriteVao}) glDeleteVertexArrays(1, &v);
}

void FrameData::Upload(const FrameScene& scene, const RenderSettings& settings) {
  UploadWater(scene);
  UploadDiffuse(scene, settings);
  LayOutPlace(scene);
}

void FrameData::UploadWater(const FrameScene& scene) {
  const bool deviceMesh = scene.deviceSurface != nullptr && scene.deviceSurface->Written();
  hasMesh = deviceMesh || !scene.surface.Empty();
  meshDrawCommand = 0;
  if (deviceMesh) {  // no upload: the buffers were written in place (CUDA-GL interop), the count too
    meshDrawCommand = scene.deviceSurface->DrawCommandBuffer();
    meshVertexCount = 0;
    meshIndexCount = 0;
    glVertexArrayVertexBuffer(meshVao, 0, scene.deviceSurface->PositionBuffer(), 0, 3 * sizeof(float));
    glVertexArrayVertexBuffer(meshVao, 1, scene.deviceSurface->NormalBuffer(), 0, 3 * sizeof(float));
    glVertexArrayElementBuffer(meshVao, 0);
  } else if (hasMesh) {
    const MeshView& s = scene.surface;
    meshVertexCount = s.vertexCount;
    meshIndexCount = s.indices ? s.indexCount : 0;
    meshPositions.Upload(s.positions, sizeof(float) * 3 * s.vertexCount);
    if (s.normals) {
      meshNormals.Upload(s.normals, sizeof(float) * 3 * s.vertexCount);
    } else {
      m_staging.assign(3 * static_cast<size_t>(s.vertexCount), 0.0f);  // no normals: face up (flat, never black)
      for (int i = 0; i < s.vertexCount; ++i) m_staging[3 * static_cast<size_t>(i) + 1] = 1.0f;
      meshNormals.Upload(m_staging.data(), sizeof(float) * m_staging.size());
    }
    if (meshIndexCount > 0) meshIndices.Upload(s.indices, sizeof(uint32_t) * meshIndexCount);
    glVertexArrayVertexBuffer(meshVao, 0, meshPositions.id, 0, 3 * sizeof(float));
    glVertexArrayVertexBuffer(meshVao, 1, meshNormals.id, 0, 3 * sizeof(float));
    glVertexArrayElementBuffer(meshVao, meshIndexCount > 0 ? meshIndices.id : 0);
  }
  const ParticleView& p = scene.particles;
  const bool drawParticles = p.count > 0 && p.position && (scene.mode == RenderMode::kParticles || !hasMesh);
  particleCount = drawParticles ? p.count : 0;
  if (drawParticles) {
    m_staging.resize(4 * static_cast<size_t>(p.count));
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
      float* o = &m_staging[4 * static_cast<size_t>(i)];
      o[0] = p.position[i].x;
      o[1] = p.position[i].y;
      o[2] = p.position[i].z;
      o[3] = s;
    }
    particles.Upload(m_staging.data(), sizeof(float) * m_staging.size());
    glVertexArrayVertexBuffer(spriteVao, 0, particles.id, 0, 4 * sizeof(float));
  }
  const bool water = scene.mode == RenderMode::kWater;
  waterFromMesh = water && hasMesh;
  waterFromSprites = water && !hasMesh && particleCount > 0;
}

void FrameData::UploadDiffuse(const FrameScene& scene, const RenderSettings& settings) {
  const DiffuseView& d = scene.diffuse;
  diffuseCount = (settings.diffuse && scene.mode == RenderMode::kWater && d.position && d.velocity) ? d.count : 0;
  if (diffuseCount <= 0) {
    diffuseCount = 0;
    return;
  }
  m_staging.resize(8 * static_cast<size_t>(diffuseCount));
  for (int i = 0; i < diffuseCount; ++i) {
    float* o = &m_staging[8 * static_cast<size_t>(i)];
    const sim::Vec4 p = d.position[i], v = d.velocity[i];
    o[0] = p.x, o[1] = p.y, o[2] = p.z, o[3] = p.w;
    o[4] = v.x, o[5] = v.y, o[6] = v.z, o[7] = v.w;
  }
  diffuse.Upload(m_staging.data(), sizeof(float) * m_staging.size());
}

void FrameData::LayOutPlace(const FrameScene& scene) {
  solids.clear();
  glass.clear();
  const glm::vec3 lo = V(scene.tank.min), hi = V(scene.tank.max);
  const glm::vec3 size = glm::max(hi - lo, glm::vec3(1e-3f));
  const float tankSize = std::max({size.x, size.y, size.z});
  const float table = std::max(scene.tableHeight, 0.0f);
  tableTop = lo.y - 1e-4f * tankSize;  // a hair below the tank floor: the water's bottom never fights with it
  groundY = table > 0.0f ? lo.y - table : tableTop;
  const float extent = std::max(12.0f * tankSize, 40.0f);
  checker = std::max(0.4f, tankSize / 4.0f);
  fade = 0.45f * extent;
  const glm::vec3 centre = 0.5f * (lo + hi);
  glm::vec3 placeLo = lo, placeHi = hi;

  const size_t groundDraw = solids.size();
  if (scene.drawFloor && table > 0.0f) LayOutTable(lo, hi, table, &placeLo, &placeHi);
  if (scene.drawFloor) LayOutGround(groundDraw, placeLo, placeHi, centre, extent);
  LayOutSolids(scene);
  if (scene.drawTank) LayOutGlass(lo, hi, tankSize);  // glass: five panes (no lid) and twelve edge bars

  // The sun's view: an orthographic box around the tank, the table and what stands above them.
  placeHi.y = std::max(placeHi.y, hi.y + 0.5f * tankSize);
  m_shadowCentre = 0.5f * (placeLo + placeHi);
  m_shadowRadius = 0.5f * glm::length(placeHi - placeLo) + 1e-3f;
  shadowRange = 4.0f * m_shadowRadius;
}

// A wooden table: a top a little wider than the tank, four legs; the place grows to the ground around
// it, where its shadow falls.
void FrameData::LayOutTable(glm::vec3 lo, glm::vec3 hi, float table, glm::vec3* placeLo, glm::vec3* placeHi) {
  const glm::vec3 size = glm::max(hi - lo, glm::vec3(1e-3f));
  const float margin = std::max(0.1f, 0.35f * std::max(size.x, size.z));
  const float thickness = std::clamp(0.12f * table, 0.02f, 0.05f), leg = std::clamp(0.06f * table, 0.02f, 0.06f);
  const glm::vec3 topLo(lo.x - margin, tableTop - thickness, lo.z - margin);
  const glm::vec3 topHi(hi.x + margin, tableTop, hi.z + margin);
  auto box = [&](glm::vec3 a, glm::vec3 b) {
    SolidDraw d;
    d.model = BoxModel(a, b);
    d.color = glm::vec3(0.62f, 0.42f, 0.25f);
    d.material = Material::kWood;
    d.buffer = cube.id;
    d.count = cubeVertices;
    solids.push_back(d);
  };
  box(topLo, topHi);
  const float inset = 0.5f * leg + 0.03f;
  for (int k = 0; k < 4; ++k) {
    const float x = (k & 1) ? topHi.x - inset : topLo.x + inset, z = (k & 2) ? topHi.z - inset : topLo.z + inset;
    box(glm::vec3(x - 0.5f * leg, groundY, z - 0.5f * leg), glm::vec3(x + 0.5f * leg, topLo.y, z + 0.5f * leg));
  }
  // The sun's view reaches the ground around the table, where the table's shadow falls.
  *placeLo = glm::min(*placeLo, topLo - glm::vec3(table, 0.0f, table));
  *placeHi = glm::max(*placeHi, topHi + glm::vec3(table, 0.0f, table));
  placeLo->y = groundY;
}

void FrameData::LayOutGround(size_t groundDraw, glm::vec3 placeLo, glm::vec3 placeHi, glm::vec3 centre, float extent) {
  // The ground: the part under the sun's shadow map (around the tank and where the table's shadow
  // falls) with the shadowed program, the rest to the horizon without it, in five quads.
  auto ground = [&](glm::vec2 a, glm::vec2 b, bool shadowed) {
    if (b.x <= a.x || b.y <= a.y) return;
    SolidDraw d;
    d.model = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0.5f * (a.x + b.x), groundY, 0.5f * (a.y + b.y))),
                         glm::vec3(b.x - a.x, 1.0f, b.y - a.y));
    d.color = glm::vec3(0.80f, 0.76f, 0.68f);
    d.material = Material::kGround;
    d.buffer = quad.id;
    d.count = 6;
    d.castsShadow = false;
    d.receivesShadow = shadowed;
    solids.insert(solids.begin() + static_cast<std::ptrdiff_t>(groundDraw), d);
  };
  const glm::vec2 lo2(placeLo.x, placeLo.z), hi2(placeHi.x, placeHi.z);
  const glm::vec2 far0(centre.x - 0.5f * extent, centre.z - 0.5f * extent), far1(centre.x + 0.5f * extent, centre.z + 0.5f * extent);
  ground(lo2, hi2, true);
  ground(far0, glm::vec2(far1.x, lo2.y), false);                 // in front of the tank's region
  ground(glm::vec2(far0.x, hi2.y), far1, false);                 // behind it
  ground(glm::vec2(far0.x, lo2.y), glm::vec2(lo2.x, hi2.y), false);  // to its left
  ground(glm::vec2(hi2.x, lo2.y), glm::vec2(far1.x, hi2.y), false);  // to its right
}

// The obstacles, then the scene's meshes (paddles, controllers) in one buffer, one draw each.
void FrameData::LayOutSolids(const FrameScene& scene) {
  for (const sim::Aabb& box : scene.obstacles) {
    SolidDraw d;
    d.model = BoxModel(V(box.min), V(box.max));
    d.color = glm::vec3(0.55f, 0.52f, 0.50f);
    d.buffer = cube.id;
    d.count = cubeVertices;
    solids.push_back(d);
  }
  m_staging.clear();
  const size_t firstMeshDraw = solids.size();
  for (const SolidMesh& solid : scene.solids) {
    SolidDraw d;
    d.model = solid.model;
    d.color = solid.color;
    if (solid.mesh.Empty()) {
      d.buffer = cube.id;
      d.count = cubeVertices;
    } else {
      const MeshView& s = solid.mesh;
      const int n = s.indices ? s.indexCount : s.vertexCount;
      d.first = static_cast<int>(m_staging.size() / 6);
      d.count = n;
      for (int k = 0; k < n; ++k) {
        const uint32_t i = s.indices ? s.indices[k] : static_cast<uint32_t>(k);
        for (int c = 0; c < 3; ++c) m_staging.push_back(s.positions[3 * i + c]);
        for (int c = 0; c < 3; ++c) m_staging.push_back(s.normals ? s.normals[3 * i + c] : (c == 1 ? 1.0f : 0.0f));
      }
    }
    solids.push_back(d);
  }
  if (!m_staging.empty()) {
    solidTriangles.Upload(m_staging.data(), m_staging.size() * sizeof(float));
    for (size_t k = firstMeshDraw; k < solids.size(); ++k) {
      if (solids[k].buffer == 0) solids[k].buffer = solidTriangles.id;
    }
  }
}

void FrameData::LayOutGlass(glm::vec3 lo, glm::vec3 hi, float tankSize) {
  const glm::vec3 centre = 0.5f * (lo + hi);
  GlassDraw panes;
  panes.model = BoxModel(lo, hi);
  panes.count = cubeVertices;
  panes.panes = true;
  panes.centre = centre;
  glass.push_back(panes);
  const float bar = std::clamp(0.012f * tankSize, 0.002f, 0.02f);
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int i = 0; i < 4; ++i) {
      glm::vec3 from, to;
      from[axis] = lo[axis];
      to[axis] = hi[axis];
      from[a] = to[a] = (i & 1) ? hi[a] : lo[a];
      from[b] = to[b] = (i & 2) ? hi[b] : lo[b];
      GlassDraw e;
      e.model = BoxModel(glm::min(from, to) - glm::vec3(0.5f * bar), glm::max(from, to) + glm::vec3(0.5f * bar));
      e.count = cubeVertices;
      e.opacity = 0.45f;
      e.centre = 0.5f * (from + to);
      glass.push_back(e);
    }
  }
}

void FrameData::BindView(const FrameScene& scene, const View& v, const RendererConfig& config, glm::vec2 targetSize) {
  const glm::vec3 sun = glm::normalize(config.sunDirection);
  // The sun's camera (the same for every view).
  const glm::vec3 lo = V(scene.tank.min), hi = V(scene.tank.max);
  const float radius = m_shadowRadius;
  const glm::vec3 up = std::abs(sun.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
  shadowViewProj = glm::ortho(-radius, radius, -radius, radius, 0.0f, shadowRange) *
                   glm::lookAt(m_shadowCentre + sun * (2.0f * radius), m_shadowCentre, up);

  ViewUniforms u;
  u.view = v.view;
  u.proj = v.projection;
  u.viewProj = v.projection * v.view;
  u.invViewProj = glm::inverse(u.viewProj);
  u.shadowViewProj = shadowViewProj;
  u.eye = glm::vec4(glm::vec3(glm::inverse(v.view)[3]), 1.0f);
  u.sun = glm::vec4(sun, 0.0f);
  u.viewport = glm::vec4(v.x, v.y, v.width, v.height);
  u.absorption = glm::vec4(config.waterAbsorption * scene.absorptionScale, 0.0f);
  u.waterColor = glm::vec4(config.waterColor, 1.0f);
  u.particle = glm::vec4(scene.particles.radius, 0.5f * v.projection[1][1] * v.height, scene.diffuse.radius, 0.0f);
  const float ior = std::max(config.waterIor, 1.0f);
  const float f0 = ((ior - 1.0f) / (ior + 1.0f)) * ((ior - 1.0f) / (ior + 1.0f));
  u.optics = glm::vec4(f0, ior, 0.0f, shadowRange);
  u.target = glm::vec4(targetSize, 0.0f, 0.0f);
  u.tankMin = glm::vec4(lo, std::max(scene.absorptionScale, 1e-6f));
  u.tankMax = glm::vec4(hi, 0.0f);
  u.place = glm::vec4(groundY, checker, fade, tableTop);
  glNamedBufferSubData(uniforms.id, 0, sizeof(u), &u);
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, uniforms.id);
}

void FrameData::SetViewportOrigin(glm::vec2 origin) {
  glNamedBufferSubData(uniforms.id, offsetof(ViewUniforms, viewport), sizeof(glm::vec2), &origin);
}

void FrameData::DrawWater() const {
  if (waterFromMesh) {
    glBindVertexArray(meshVao);
    if (meshDrawCommand != 0) {  // the vertex count lives in the GL buffer its writer filled
      glBindBuffer(GL_DRAW_INDIRECT_BUFFER, meshDrawCommand);
      glDrawArraysIndirect(GL_TRIANGLES, nullptr);
      glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    } else if (meshIndexCount > 0) {
      glDrawElements(GL_TRIANGLES, meshIndexCount, GL_UNSIGNED_INT, nullptr);
    } else {
      glDrawArrays(GL_TRIANGLES, 0, meshVertexCount);
    }
  } else if (waterFromSprites) {
    glBindVertexArray(spriteVao);
    glDrawArrays(GL_POINTS, 0, particleCount);
  }
}

void FrameData::DrawDiffuse() const {
  if (diffuseCount <= 0) return;
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, diffuse.id);
  glBindVertexArray(emptyVao);
  glDrawArrays(GL_TRIANGLES, 0, 6 * diffuseCount);
}

}  // namespace sphxr::render
