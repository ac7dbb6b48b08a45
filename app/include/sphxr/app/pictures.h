#pragma once
// Pictures of a run without a display: PNG files (stb_image_write), the FrameScene of a scene and its
// particles, and an offscreen renderer over an EGL surfaceless context (--screenshot, --frames).
#include <memory>
#include <string>

#include "sphxr/app/snapshot.h"
#include "sphxr/common/status.h"
#include "sphxr/render/gl_context.h"
#include "sphxr/render/renderer.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/params.h"

namespace sphxr::app {

/// Writes RGBA pixels (rows bottom-up, as OpenGL reads them) as an RGB PNG, top row first.
Status WritePng(const std::string& path, const render::Image& image);
/// Reads a PNG into RGBA rows bottom-up (tests).
Status ReadPng(const std::string& path, render::Image* out);

/// The FrameScene of a scene's tank and obstacles with the particles of `fluid` (no surface mesh: water
/// mode draws the particles as water). The arrays of `fluid` must outlive the returned scene.
render::FrameScene MakeFrameScene(const sim::SceneSetup& scene, const sim::HostFluid& fluid, render::RenderMode mode,
                                  render::ParticleColor color = render::ParticleColor::kSpeed);

/// The full FrameScene of a snapshot, what the desktop window, the headset and headless pictures draw:
/// tank, obstacles, particles, the water surface (water mode, when the snapshot has one; else the
/// particles are drawn as water) and the paddles (render::SolidMesh per box and capsule at the body's
/// pose). The snapshot must outlive the returned scene. GPU path: a snapshot whose surface stayed on the
/// device (SimSnapshot::surfaceOnDevice) draws `deviceSurface` (GL buffers written in place, see
/// InteropSurface in app/src/sim_worker.h) as FrameScene::deviceSurface instead.
render::FrameScene MakeFrameScene(const SimSnapshot& snapshot, render::RenderMode mode,
                                  render::ParticleColor color = render::ParticleColor::kSpeed,
                                  const render::InteropMesh* deviceSurface = nullptr);
/// The solids of one paddle at its pose (appended to `out`).
void AppendPaddleSolids(const PaddlePose& paddle, std::vector<render::SolidMesh>* out);
/// A controller held at `grip` (scene coordinates; OpenXR's grip space): a dark handle and its ring.
void AppendControllerSolids(const interaction::Pose& grip, std::vector<render::SolidMesh>* out);

/// Renders frames of a run into PNG files without a display.
class OfflinePictures {
 public:
  /// Creates the EGL context, the renderer and a width x height target. Errors are one line
  /// ("no EGL display ...", "needs OpenGL 4.5 ...").
  static Status Create(int width, int height, std::unique_ptr<OfflinePictures>* out, bool glDebug = false,
                       render::RenderQuality quality = render::RenderQuality::kHigh);
  /// Draws the scene from the camera that frames the tank and writes `path`.
  Status Write(const render::FrameScene& frame, const std::string& path);
  int Width() const { return m_width; }
  int Height() const { return m_height; }

 private:
  OfflinePictures() = default;
  std::unique_ptr<render::HeadlessContext> m_context;
  std::unique_ptr<render::OffscreenTarget> m_target;
  std::unique_ptr<render::Renderer> m_renderer;
  int m_width = 0, m_height = 0;
};

/// Full path of `program` when it is on the PATH, else empty.
std::string FindOnPath(const std::string& program);

}  // namespace sphxr::app
