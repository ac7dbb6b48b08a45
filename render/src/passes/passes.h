#pragma once
// The renderer's passes. Each one owns its programs, sets the GL state it needs and draws one thing;
// Renderer::Draw (renderer.cpp) is the list that runs them. docs/dev/rendering.md describes each.
#include <epoxy/gl.h>

#include "frame_targets.h"
#include "gl_util.h"
#include "passes/frame_data.h"
#include "sphxr/render/renderer.h"

namespace sphxr::render {

/// What a pass sees: the scene, the view being drawn, the frame's upload and the targets.
struct PassContext {
  const FrameScene& scene;
  const View& view;
  FrameData& data;
  FrameTargets& targets;
  const RenderSettings& settings;
};

/// Binds the frame targets' scene framebuffer (colour and depth) for a view, and clears its depth.
void BeginScene(const PassContext& ctx);
/// Binds the view's own framebuffer and viewport.
void BeginViewFramebuffer(const PassContext& ctx);

/// The sky: one full-screen triangle (the same function the water and the glass reflect).
class SkyPass {
 public:
  Status Create() { return LinkProgram("sky", &m_program.id); }
  void Run(const PassContext& ctx) const;

 private:
  Program m_program;
};

/// The sun's depth maps, once per frame: the opaque casters (table, obstacles, paddles) and the water's
/// nearest surface (for the light that crosses it).
class ShadowPass {
 public:
  Status Create() { return LinkProgram("shadow", &m_program.id); }
  void Run(const FrameData& data, FrameTargets& targets, const RenderSettings& settings) const;

 private:
  Program m_program;
};

/// The opaque scene: ground, table, obstacles, paddles and controllers, lit by the sun with its
/// shadow; in particle mode the particles as coloured spheres.
class OpaquePass {
 public:
  Status Create();
  void Run(const PassContext& ctx) const;

 private:
  Program m_solid, m_solidShadowed, m_particles;
};

/// The tank's glass: the panes turned away from the eye (and the far edge bars) into the opaque scene,
/// so that the water refracts them; the near panes and bars over everything.
class GlassPass {
 public:
  Status Create() { return LinkProgram("glass", &m_program.id); }
  void RunFar(const PassContext& ctx) const { Run(ctx, /*far=*/true); }
  void RunNear(const PassContext& ctx) const { Run(ctx, /*far=*/false); }

 private:
  void Run(const PassContext& ctx, bool far) const;
  Program m_program;
};

/// Spray, foam and bubbles as soft sprites stretched along their velocity: bubbles into the opaque
/// scene (seen through the water's refraction), spray and foam over the water.
class DiffusePass {
 public:
  Status Create();
  void RunBubbles(const PassContext& ctx) const;
  void RunSprayAndFoam(const PassContext& ctx) const;

 private:
  Program m_bubbles, m_surface;
};

/// The water's length along each pixel's ray into the thickness target (additive).
class WaterThicknessPass {
 public:
  Status Create();
  void Run(const PassContext& ctx) const;

 private:
  Program m_mesh, m_sprites;
};

/// The opaque scene's colour and depth from the frame targets into the view's framebuffer.
class PresentPass {
 public:
  Status Create() { return LinkProgram("present", &m_program.id); }
  void Run(const PassContext& ctx) const;

 private:
  Program m_program;
};

/// The water's nearest surface: its depth, then its shading over the opaque scene (refraction, Fresnel
/// reflection, Beer-Lambert absorption, the sun's glint).
class WaterPass {
 public:
  Status Create();
  void Run(const PassContext& ctx) const;

 private:
  Program m_depthMesh, m_shadeMesh, m_shadeMeshShadowed, m_shadeSprites, m_shadeSpritesShadowed;
};

}  // namespace sphxr::render
