// The passes that draw into the frame targets' opaque scene: sky, opaque solids, the sun's shadow maps,
// and present, which copies the opaque scene into the view's framebuffer.
#include <glm/gtc/type_ptr.hpp>

#include "passes/passes.h"

namespace sphxr::render {

void BeginScene(const PassContext& ctx) {
  ctx.data.SetViewportOrigin(glm::vec2(0.0f));
  glBindFramebuffer(GL_FRAMEBUFFER, ctx.targets.SceneFramebuffer());
  glViewport(0, 0, ctx.view.width, ctx.view.height);
  glScissor(0, 0, ctx.view.width, ctx.view.height);
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
}

void BeginViewFramebuffer(const PassContext& ctx) {
  const View& v = ctx.view;
  ctx.data.SetViewportOrigin(glm::vec2(v.x, v.y));
  glBindFramebuffer(GL_FRAMEBUFFER, v.framebuffer);
  glViewport(v.x, v.y, v.width, v.height);
  glScissor(v.x, v.y, v.width, v.height);
}

void SkyPass::Run(const PassContext& ctx) const {
  // After the opaque scene, at the far plane with the depth test: only the pixels nothing covers.
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glUseProgram(m_program.id);
  glBindVertexArray(ctx.data.emptyVao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
}

void ShadowPass::Run(const FrameData& data, FrameTargets& targets, const RenderSettings& settings) const {
  targets.EnsureShadow(settings.shadowMapSize);
  if (settings.shadowMapSize <= 0) return;
  const int size = targets.ShadowSize();
  const float far = 1.0f;
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glUseProgram(m_program.id);
  // Opaque casters.
  glBindFramebuffer(GL_FRAMEBUFFER, targets.ShadowFramebuffer());
  glViewport(0, 0, size, size);
  glScissor(0, 0, size, size);
  glClearNamedFramebufferfv(targets.ShadowFramebuffer(), GL_DEPTH, 0, &far);
  glBindVertexArray(data.solidVao);
  for (const SolidDraw& d : data.solids) {
    if (!d.castsShadow) continue;
    glProgramUniformMatrix4fv(m_program.id, 0, 1, GL_FALSE, glm::value_ptr(d.model));
    glVertexArrayVertexBuffer(data.solidVao, 0, d.buffer, 0, 6 * sizeof(float));
    glDrawArrays(GL_TRIANGLES, d.first, d.count);
  }
  // The water's surface nearest the sun.
  glBindFramebuffer(GL_FRAMEBUFFER, targets.WaterShadowFramebuffer());
  glClearNamedFramebufferfv(targets.WaterShadowFramebuffer(), GL_DEPTH, 0, &far);
  if (data.waterFromMesh) {
    const glm::mat4 identity(1.0f);
    glProgramUniformMatrix4fv(m_program.id, 0, 1, GL_FALSE, glm::value_ptr(identity));
    data.DrawWater();
  }
}

Status OpaquePass::Create() {
  if (Status s = LinkProgram("solid", &m_solid.id); !s) return s;
  if (Status s = LinkProgram("solid (shadowed)", &m_solidShadowed.id); !s) return s;
  return LinkProgram("particles", &m_particles.id);
}

void OpaquePass::Run(const PassContext& ctx) const {
  const FrameData& data = ctx.data;
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  ctx.targets.BindShadowMaps();
  glBindVertexArray(data.solidVao);
  for (const SolidDraw& d : data.solids) {
    const GLuint solid = ctx.settings.shadowMapSize > 0 && d.receivesShadow ? m_solidShadowed.id : m_solid.id;
    glUseProgram(solid);
    glProgramUniformMatrix4fv(solid, 0, 1, GL_FALSE, glm::value_ptr(d.model));
    glProgramUniform4f(solid, 1, d.color.r, d.color.g, d.color.b, 1.0f);
    glProgramUniform1i(solid, 2, static_cast<int>(d.material));
    glVertexArrayVertexBuffer(data.solidVao, 0, d.buffer, 0, 6 * sizeof(float));
    glDrawArrays(GL_TRIANGLES, d.first, d.count);
  }
  if (ctx.scene.mode == RenderMode::kParticles && data.particleCount > 0) {
    glUseProgram(m_particles.id);
    glBindVertexArray(data.spriteVao);
    glDrawArrays(GL_POINTS, 0, data.particleCount);
  }
}

void PresentPass::Run(const PassContext& ctx) const {
  ctx.targets.BindSceneTextures();
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_ALWAYS);
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glUseProgram(m_program.id);
  glBindVertexArray(ctx.data.emptyVao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthFunc(GL_LESS);
}

}  // namespace sphxr::render
