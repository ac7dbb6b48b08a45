#pragma once
// The textures the passes draw into and read from. Grown to the largest view seen (never shrunk); a
// view draws into their lower-left corner.
//   scene       the opaque scene: colour (RGBA8, as the views) and depth (32F), kept as textures so that the
//               water can refract what lies behind it
//   thickness   the water's length along each pixel's ray (R32F, additive)
//   shadow      the sun's depth maps: opaque casters (compared, 2x2 PCF) and the nearest water surface
#include <epoxy/gl.h>

namespace sphxr::render {

/// Texture units the passes sample (shaders.h binds the same numbers).
inline constexpr GLuint kUnitThickness = 0, kUnitSceneColor = 1, kUnitSceneDepth = 2, kUnitShadow = 4,
                        kUnitWaterShadow = 5;

class FrameTargets {
 public:
  FrameTargets() = default;
  ~FrameTargets();
  FrameTargets(const FrameTargets&) = delete;
  FrameTargets& operator=(const FrameTargets&) = delete;

  /// Grows the view-sized targets to hold a w x h view.
  void EnsureView(int w, int h);
  /// (Re)creates the sun's depth maps at `size` texels a side (0: none, and 1x1 maps that read "lit").
  void EnsureShadow(int size);

  int Width() const { return m_w; }
  int Height() const { return m_h; }
  int ShadowSize() const { return m_shadowSize; }
  GLuint SceneFramebuffer() const { return m_sceneFbo; }
  GLuint ThicknessFramebuffer() const { return m_thicknessFbo; }
  GLuint ShadowFramebuffer() const { return m_shadowFbo; }
  GLuint WaterShadowFramebuffer() const { return m_waterShadowFbo; }

  /// Binds the shadow maps to their units (every pass that lights a surface samples them).
  void BindShadowMaps() const;
  /// Binds the scene's colour and depth and the thickness to their units (the passes into the view's
  /// framebuffer; never while drawing into the scene itself).
  void BindSceneTextures() const;

 private:
  void ReleaseView();
  void ReleaseShadow();
  int m_w = 0, m_h = 0;
  GLuint m_sceneFbo = 0, m_sceneColor = 0, m_sceneDepth = 0;
  GLuint m_thicknessFbo = 0, m_thickness = 0;
  int m_shadowSize = -1;
  GLuint m_shadowFbo = 0, m_shadow = 0, m_waterShadowFbo = 0, m_waterShadow = 0;
};

}  // namespace sphxr::render
