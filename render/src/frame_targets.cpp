#include "frame_targets.h"

#include <algorithm>

namespace sphxr::render {

namespace {

GLuint Texture(GLenum format, int w, int h, GLenum filter) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, format, w, h);
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, filter);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, filter);
  glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return t;
}

GLuint DepthMap(int size, bool compare) {
  GLuint t = Texture(GL_DEPTH_COMPONENT32F, size, size, compare ? GL_LINEAR : GL_NEAREST);
  if (compare) {
    glTextureParameteri(t, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(t, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  }
  return t;
}

GLuint DepthFramebuffer(GLuint depth) {
  GLuint fbo = 0;
  glCreateFramebuffers(1, &fbo);
  glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth, 0);
  glNamedFramebufferDrawBuffer(fbo, GL_NONE);
  glNamedFramebufferReadBuffer(fbo, GL_NONE);
  return fbo;
}

}  // namespace

FrameTargets::~FrameTargets() {
  ReleaseView();
  ReleaseShadow();
}

void FrameTargets::ReleaseView() {
  glDeleteFramebuffers(1, &m_sceneFbo);
  glDeleteFramebuffers(1, &m_thicknessFbo);
  glDeleteTextures(1, &m_sceneColor);
  glDeleteTextures(1, &m_sceneDepth);
  glDeleteTextures(1, &m_thickness);
  m_sceneFbo = m_thicknessFbo = m_sceneColor = m_sceneDepth = m_thickness = 0;
}

void FrameTargets::ReleaseShadow() {
  glDeleteFramebuffers(1, &m_shadowFbo);
  glDeleteFramebuffers(1, &m_waterShadowFbo);
  glDeleteTextures(1, &m_shadow);
  glDeleteTextures(1, &m_waterShadow);
  m_shadowFbo = m_waterShadowFbo = m_shadow = m_waterShadow = 0;
}

void FrameTargets::EnsureView(int w, int h) {
  if (w <= m_w && h <= m_h && m_sceneFbo) return;
  ReleaseView();
  m_w = std::max(w, m_w);
  m_h = std::max(h, m_h);
  m_sceneColor = Texture(GL_RGBA8, m_w, m_h, GL_LINEAR);  // the views are 8-bit too: no precision lost
  m_sceneDepth = Texture(GL_DEPTH_COMPONENT32F, m_w, m_h, GL_NEAREST);
  glCreateFramebuffers(1, &m_sceneFbo);
  glNamedFramebufferTexture(m_sceneFbo, GL_COLOR_ATTACHMENT0, m_sceneColor, 0);
  glNamedFramebufferTexture(m_sceneFbo, GL_DEPTH_ATTACHMENT, m_sceneDepth, 0);
  m_thickness = Texture(GL_R32F, m_w, m_h, GL_NEAREST);
  glCreateFramebuffers(1, &m_thicknessFbo);
  glNamedFramebufferTexture(m_thicknessFbo, GL_COLOR_ATTACHMENT0, m_thickness, 0);
}

void FrameTargets::EnsureShadow(int size) {
  if (size == m_shadowSize && m_shadowFbo) return;
  ReleaseShadow();
  m_shadowSize = size;
  const int texels = std::max(size, 1);
  m_shadow = DepthMap(texels, /*compare=*/true);
  m_waterShadow = DepthMap(texels, /*compare=*/false);
  m_shadowFbo = DepthFramebuffer(m_shadow);
  m_waterShadowFbo = DepthFramebuffer(m_waterShadow);
  const float far = 1.0f;  // an empty map: every receiver is lit, no water above it
  glClearNamedFramebufferfv(m_shadowFbo, GL_DEPTH, 0, &far);
  glClearNamedFramebufferfv(m_waterShadowFbo, GL_DEPTH, 0, &far);
}

void FrameTargets::BindShadowMaps() const {
  glBindTextureUnit(kUnitShadow, m_shadow);
  glBindTextureUnit(kUnitWaterShadow, m_waterShadow);
}

void FrameTargets::BindSceneTextures() const {
  glBindTextureUnit(kUnitThickness, m_thickness);
  glBindTextureUnit(kUnitSceneColor, m_sceneColor);
  glBindTextureUnit(kUnitSceneDepth, m_sceneDepth);
}

}  // namespace sphxr::render
