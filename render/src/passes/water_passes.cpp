// The water's passes: its thickness into the frame targets, then its depth and shading into the view.
#include "passes/passes.h"

namespace sphxr::render {

Status WaterThicknessPass::Create() {
  if (Status s = LinkProgram("water thickness (mesh)", &m_mesh.id); !s) return s;
  return LinkProgram("water thickness (sprites)", &m_sprites.id);
}

void WaterThicknessPass::Run(const PassContext& ctx) const {
  const FrameData& data = ctx.data;
  if (!data.waterFromMesh && !data.waterFromSprites) return;
  glBindFramebuffer(GL_FRAMEBUFFER, ctx.targets.ThicknessFramebuffer());
  glViewport(0, 0, ctx.view.width, ctx.view.height);
  glScissor(0, 0, ctx.view.width, ctx.view.height);
  const float zero[4] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, zero);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  glUseProgram(data.waterFromMesh ? m_mesh.id : m_sprites.id);
  data.DrawWater();
  glDisable(GL_BLEND);
}

Status WaterPass::Create() {
  if (Status s = LinkProgram("water depth (mesh)", &m_depthMesh.id); !s) return s;
  if (Status s = LinkProgram("water shade (mesh)", &m_shadeMesh.id); !s) return s;
  if (Status s = LinkProgram("water shade (mesh, shadowed)", &m_shadeMeshShadowed.id); !s) return s;
  if (Status s = LinkProgram("water shade (sprites)", &m_shadeSprites.id); !s) return s;
  return LinkProgram("water shade (sprites, shadowed)", &m_shadeSpritesShadowed.id);
}

void WaterPass::Run(const PassContext& ctx) const {
  const FrameData& data = ctx.data;
  if (!data.waterFromMesh && !data.waterFromSprites) return;
  ctx.targets.BindSceneTextures();
  ctx.targets.BindShadowMaps();
  const bool shadows = ctx.settings.shadowMapSize > 0;
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  if (data.waterFromSprites) {
    // Sprites compute their depth per fragment, and two programs need not round it alike: shaded in one
    // pass with the depth test, so that the nearest sphere's shading is what stays.
    glUseProgram(shadows ? m_shadeSpritesShadowed.id : m_shadeSprites.id);
    data.DrawWater();
    return;
  }
  // The nearest water surface's depth (it stays in the view's depth buffer: the headset gets it).
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glUseProgram(m_depthMesh.id);
  data.DrawWater();
  // That surface, shaded over the opaque scene behind it.
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_LEQUAL);
  glUseProgram(shadows ? m_shadeMeshShadowed.id : m_shadeMesh.id);
  data.DrawWater();
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
}

}  // namespace sphxr::render
