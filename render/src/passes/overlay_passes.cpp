// The see-through passes: the tank's glass and the diffuse particles (spray, foam, bubbles). Both blend
// premultiplied colour over what is there: dst = src + dst (1 - src.a).
#include <glm/gtc/type_ptr.hpp>

#include "passes/passes.h"

namespace sphxr::render {

void GlassPass::Run(const PassContext& ctx, bool far) const {
  const FrameData& data = ctx.data;
  if (data.glass.empty()) return;
  const glm::vec3 eye = glm::vec3(glm::inverse(ctx.view.view)[3]);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_FALSE);
  glEnable(GL_CULL_FACE);
  glUseProgram(m_program.id);
  glBindVertexArray(data.solidVao);
  glVertexArrayVertexBuffer(data.solidVao, 0, data.cube.id, 0, 6 * sizeof(float));
  const glm::vec3 tankCentre = data.glass.front().centre;
  for (const GlassDraw& g : data.glass) {
    glProgramUniformMatrix4fv(m_program.id, 0, 1, GL_FALSE, glm::value_ptr(g.model));
    if (g.panes) {
      // The panes turned away from the eye lie behind the water; those turned towards it in front.
      glCullFace(far ? GL_FRONT : GL_BACK);
      glProgramUniform4f(m_program.id, 1, 0.90f, 0.97f, 0.96f, 0.03f);
      glDrawArrays(GL_TRIANGLES, 0, 12);   // x+ and x-
      glDrawArrays(GL_TRIANGLES, 18, 18);  // y- (the floor), z+, z- (no lid)
    } else {
      const bool behind = glm::distance(eye, g.centre) > glm::distance(eye, tankCentre);
      if (behind != far) continue;
      glCullFace(GL_BACK);
      glProgramUniform4f(m_program.id, 1, 0.55f, 0.78f, 0.74f, g.opacity);
      glDrawArrays(GL_TRIANGLES, 0, g.count);
    }
  }
  glDisable(GL_CULL_FACE);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}

Status DiffusePass::Create() {
  if (Status s = LinkProgram("diffuse (bubbles)", &m_bubbles.id); !s) return s;
  return LinkProgram("diffuse (spray and foam)", &m_surface.id);
}

namespace {
void DrawDiffuse(const PassContext& ctx, GLuint program) {
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_FALSE);
  glUseProgram(program);
  ctx.data.DrawDiffuse();
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}
}  // namespace

void DiffusePass::RunBubbles(const PassContext& ctx) const {
  if (ctx.data.diffuseCount > 0) DrawDiffuse(ctx, m_bubbles.id);
}

void DiffusePass::RunSprayAndFoam(const PassContext& ctx) const {
  if (ctx.data.diffuseCount > 0) DrawDiffuse(ctx, m_surface.id);
}

}  // namespace sphxr::render
