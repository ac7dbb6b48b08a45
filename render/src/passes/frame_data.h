#pragma once
// What one frame's upload holds, shared by every pass: the per-view uniform block, the static meshes,
// the water (surface mesh or particles), the diffuse particles, and the solids as a list of draws.
#include <epoxy/gl.h>

#include <glm/glm.hpp>
#include <vector>

#include "gl_util.h"
#include "sphxr/render/renderer.h"

namespace sphxr::render {

/// std140 layout of ViewBlock in shaders.h.
struct ViewUniforms {
  glm::mat4 view, proj, viewProj, invViewProj, shadowViewProj;
  glm::vec4 eye, sun, viewport, absorption, waterColor, particle, optics, target, tankMin, tankMax, place;
};

/// Materials of the solid shader (kSolidFs).
enum class Material : int { kPlain = 0, kGround = 1, kWood = 2 };

/// One solid draw: interleaved position + normal triangles in `buffer` from vertex `first`.
struct SolidDraw {
  glm::mat4 model{1.0f};
  glm::vec3 color{1.0f};
  Material material = Material::kPlain;
  GLuint buffer = 0;
  int first = 0, count = 0;
  bool castsShadow = true;
  bool receivesShadow = true;  // false: drawn with the unshadowed program (the ground beyond the sun's map)
};

/// A glass part of the tank: panes (the box without its top) or one edge bar.
struct GlassDraw {
  glm::mat4 model{1.0f};
  int first = 0, count = 0;  // vertices of the unit cube
  float opacity = 0.0f;
  glm::vec3 centre{0.0f};
  bool panes = false;
};

struct FrameData {
  FrameData();
  ~FrameData();
  FrameData(const FrameData&) = delete;
  FrameData& operator=(const FrameData&) = delete;

  /// Uploads what `scene` shows (once for all views) and lays out the place around the tank.
  void Upload(const FrameScene& scene, const RenderSettings& settings);
  /// The uniform block for `view` (the sun's matrix included), uploaded and bound to binding 0.
  void BindView(const FrameScene& scene, const View& view, const RendererConfig& config, glm::vec2 targetSize);

  // Static meshes.
  Buffer cube;  // unit cube centred at the origin: 36 vertices of position + normal (faces x+, x-, y+, y-, z+, z-)
  Buffer quad;  // unit square in y = 0, normal +y
  int cubeVertices = 0;
  GLuint emptyVao = 0, solidVao = 0, meshVao = 0, spriteVao = 0;
  Buffer uniforms;

  // The water.
  bool hasMesh = false;
  int meshVertexCount = 0, meshIndexCount = 0;
  GLuint meshDrawCommand = 0;  // a device-written mesh: its glDrawArraysIndirect buffer (else 0)
  Buffer meshPositions, meshNormals, meshIndices;
  int particleCount = 0;  // sprites uploaded (particle mode, or water without a mesh)
  Buffer particles;       // xyz + the colour scalar
  bool waterFromMesh = false, waterFromSprites = false;

  // Spray, foam and bubbles (two vec4 per particle).
  int diffuseCount = 0;
  Buffer diffuse;

  // The opaque scene and the glass.
  std::vector<SolidDraw> solids;
  std::vector<GlassDraw> glass;
  Buffer solidTriangles;  // the scene's own meshes (paddles, controllers), interleaved
  float groundY = 0.0f, checker = 0.5f, fade = 10.0f, tableTop = 0.0f;
  glm::mat4 shadowViewProj{1.0f};
  float shadowRange = 1.0f;  // m per unit of the sun's depth

  /// Moves the views' origin in the bound uniform block: (0, 0) while drawing into the frame targets,
  /// the view's own (x, y) while drawing into its framebuffer.
  void SetViewportOrigin(glm::vec2 origin);
  void DrawWater() const;    // the surface mesh or the sprites, with the bound program
  void DrawDiffuse() const;  // six vertices per diffuse particle (the diffuse programs)

 private:
  std::vector<float> m_staging;
  glm::vec3 m_shadowCentre{0.0f};
  float m_shadowRadius = 1.0f;
  void UploadWater(const FrameScene& scene);
  void UploadDiffuse(const FrameScene& scene, const RenderSettings& settings);
  void LayOutPlace(const FrameScene& scene);
  // Its parts: the table (growing the place the sun's view covers), the ground, the solids, the glass.
  void LayOutTable(glm::vec3 lo, glm::vec3 hi, float table, glm::vec3* placeLo, glm::vec3* placeHi);
  void LayOutGround(size_t groundDraw, glm::vec3 placeLo, glm::vec3 placeHi, glm::vec3 centre, float extent);
  void LayOutSolids(const FrameScene& scene);
  void LayOutGlass(glm::vec3 lo, glm::vec3 hi, float tankSize);
};

}  // namespace sphxr::render
