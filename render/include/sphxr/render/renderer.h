#pragma once
// The renderer: draws one FrameScene for any list of views (OpenGL 4.5 core). A view is a pair of
// matrices, a target framebuffer and a viewport; the renderer does not know whether views come from a
// headset (one per eye) or a desktop camera (DESIGN.md, "Shape" and "One frame").
//
// Draw(scene, views) is a list of passes (render/src/passes/, docs/dev/rendering.md):
//   upload          surface mesh, particles, diffuse particles, solids (once per frame)
//   shadow          the sun's depth maps of the opaque casters and of the water (once per frame)
//   per view, into the frame targets (the opaque scene kept as textures):
//     opaque (ground, table, obstacles, paddles; particles in particle mode), sky (where nothing is),
//     glass (far panes), bubbles, water thickness
//   per view, into the view's framebuffer:
//     present (the opaque scene's colour and depth), water (refraction of the scene behind, Fresnel
//     reflection, Beer-Lambert absorption; writes its depth), glass (near panes), spray and foam
#include <glm/glm.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/vec.h"

namespace sphxr::render {

/// One view: what the renderer draws into. `framebuffer` 0 is the default framebuffer.
struct View {
  glm::mat4 view{1.0f};        // world -> eye
  glm::mat4 projection{1.0f};  // eye -> clip (OpenGL conventions, depth -1..1)
  uint32_t framebuffer = 0;
  int x = 0, y = 0, width = 0, height = 0;  // viewport in pixels, origin bottom-left
};

/// A triangle mesh as plain arrays on the host (the CPU backend's HPMC output); xyz floats.
/// `indices` may be null: then every three vertices make a triangle.
struct MeshView {
  const float* positions = nullptr;  // 3 floats per vertex
  const float* normals = nullptr;    // 3 floats per vertex, pointing out of the water
  int vertexCount = 0;
  const uint32_t* indices = nullptr;
  int indexCount = 0;
  bool Empty() const { return positions == nullptr || vertexCount <= 0; }
};

/// What colours the particles in particle mode.
enum class ParticleColor { kSpeed, kDensityError, kActivity };
const char* ParticleColorName(ParticleColor c);

/// Fluid particles as plain host arrays (e.g. a sim::HostFluid). `velocity`, `density` and `idle` may be
/// null when the colour mode does not need them.
struct ParticleView {
  const sim::Vec4* position = nullptr;
  const sim::Vec4* velocity = nullptr;
  const float* density = nullptr;
  const int32_t* idle = nullptr;  // reuse idle count: -1 active, >= 0 reusing
  int count = 0;
  float radius = 0.01f;           // m, drawn sphere radius (about half the spacing)
  float restDensity = 1000.0f;
  float speedScale = 2.0f;        // m/s mapped to the top of the colour map
  float densityErrorScale = 0.05f;// |rho/rho0 - 1| mapped to the top of the colour map
};

enum class RenderMode { kWater, kParticles };

/// Spray, foam and bubbles (sphxr/sim/diffuse.h): positions with w = remaining lifetime (s), velocities
/// with w = the kind (0 spray, 1 foam, 2 bubble). Null or empty: none drawn.
struct DiffuseView {
  const sim::Vec4* position = nullptr;
  const sim::Vec4* velocity = nullptr;
  int count = 0;
  float radius = 0.004f;  // m, a foam sprite's half width
};
const char* RenderModeName(RenderMode m);

/// A paddle or hand: a mesh drawn with a model matrix (or a unit cube when the mesh is empty).
struct SolidMesh {
  MeshView mesh;            // empty: a unit cube centred at the origin
  glm::mat4 model{1.0f};
  glm::vec3 color{0.8f, 0.5f, 0.2f};
};

/// Everything one frame shows. Plain data: the caller owns the arrays until Draw() returns.
class InteropMesh;

struct FrameScene {
  MeshView surface;             // water surface; empty: water mode draws the particles as water
  const InteropMesh* deviceSurface = nullptr;  // water surface already in GL buffers (CUDA-GL interop);
                                               // when set and not empty it is drawn instead of `surface` spheres
  ParticleView particles;
  RenderMode mode = RenderMode::kWater;
  ParticleColor particleColor = ParticleColor::kSpeed;
  sim::Aabb tank{{0, 0, 0}, {1, 1, 1}};
  bool drawTank = true;
  std::vector<sim::Aabb> obstacles;
  std::vector<SolidMesh> solids;  // paddles, controllers
  DiffuseView diffuse;
  /// The place: the ground to the horizon and, when tableHeight > 0, a table under the tank (its top
  /// at the tank's floor, the ground tableHeight below it).
  bool drawFloor = true;
  float tableHeight = 0.85f;  // m; 0: the tank stands on the ground
  /// Multiplies RendererConfig::waterAbsorption (pure water's). Water a few centimetres deep is clear,
  /// so a picture of it raises this: app::MakeFrameScene sets it from the tank's size so that its
  /// smallest extent keeps 9 % of the red light; the default makes a decimetre read as water.
  float absorptionScale = 15.0f;
  /// Non-zero: the frame this scene belongs to. Draw calls with the same key (a headset's two eyes,
  /// drawn one swapchain image at a time) share one upload and one pass of the sun's shadow maps, and
  /// their pass times add up to the frame's (DrawStats, complete once the next frame has begun).
  uint64_t frameKey = 0;
};

/// What the renderer spends per frame: `--quality auto` lowers it with the simulation.
enum class RenderQuality { kLow, kMedium, kHigh };
const char* RenderQualityName(RenderQuality q);
bool ParseRenderQuality(const std::string& text, RenderQuality* out);
struct RenderSettings {
  int shadowMapSize = 2048;  // texels per side of the sun's depth maps; 0: no shadows
  bool diffuse = true;       // spray, foam and bubbles drawn
};
RenderSettings SettingsFor(RenderQuality q);

/// Pure water's absorption (1/m) at the dominant wavelengths of the sRGB primaries (612, 549, 465 nm),
/// from Pope & Fry, "Absorption spectrum (380-700 nm) of pure water", Applied Optics 36(33), 1997.
inline const glm::vec3 kPureWaterAbsorption{0.26f, 0.057f, 0.013f};
/// Water's index of refraction (visible light, 20 degrees C) and its Fresnel reflectance at normal incidence.
inline constexpr float kWaterIor = 1.333f;

/// Called for every GL debug message of type error (and for GL errors found by glGetError).
using GlErrorHandler = std::function<void(const std::string& message)>;

struct RendererConfig {
  /// Install the GL debug callback. On by default in debug builds; the tests turn it on always.
  bool debug =
#ifdef NDEBUG
      false;
#else
      true;
#endif
  /// What happens on a GL error: null = log it and abort() (debug builds fail loudly).
  GlErrorHandler onError;
  glm::vec3 sunDirection = glm::normalize(glm::vec3(0.35f, 0.8f, 0.45f));  // towards the sun
  glm::vec3 waterAbsorption = kPureWaterAbsorption;  // 1/m, Beer-Lambert coefficients (red goes first)
  /// The light the water body scatters back per unit of light it stops: pure water's single-scattering
  /// albedo b_b / (a + b_b), with b_b half of Morel's (1974) scattering 0.00288 (lambda/500 nm)^-4.32 /m
  /// and a as above, at the same wavelengths. Deep clear water is dark blue, never a cyan slab.
  glm::vec3 waterColor{0.0023f, 0.017f, 0.13f};
  float waterIor = kWaterIor;                   // 1: no refraction, and F0 = 0
  RenderQuality quality = RenderQuality::kHigh;
  /// Finish the GL work before and after each pass and time it on the clock (the benchmarks): exact on
  /// a software rasteriser, where a GL_TIME_ELAPSED query can hold another pass's binned work; slow.
  bool finishEachPass = false;
};

/// One pass's GPU time (GL_TIME_ELAPSED), summed over the views of a frame.
struct PassTime {
  std::string name;
  double gpuMs = 0.0;
};

/// Draw timings: CPU side of the last frame; GPU time per pass of the latest frame whose queries have
/// completed (a frame or two late: reading them never waits for the GPU).
struct DrawStats {
  double uploadMs = 0.0;
  double drawMs = 0.0;
  std::vector<PassTime> passes;  // in drawing order
  int views = 0;                 // views drawn in the frame the pass times belong to
  double GpuMs() const;          // the sum of the passes
};

class Renderer {
 public:
  /// Needs a current OpenGL 4.5 core context. Fails with one clear line when the context is older.
  static Status Create(const RendererConfig& config, std::unique_ptr<Renderer>* out);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Uploads the scene once, then draws it into every view.
  void Draw(const FrameScene& scene, std::span<const View> views);
  const DrawStats& LastStats() const { return m_stats; }
  /// GL errors seen by the debug callback since creation.
  int ErrorCount() const;
  const RendererConfig& Config() const { return m_config; }
  /// Changes what the renderer spends from the next frame on (the panel, --quality auto).
  void SetQuality(RenderQuality quality);

 private:
  struct Impl;
  explicit Renderer(const RendererConfig& config);
  RendererConfig m_config;
  std::unique_ptr<Impl> m_impl;
  DrawStats m_stats;
};

/// The sky seen along a world direction: the same formula as the sky shader and the water's
/// reflection (C++ twin, used by the tests and by the clear colour). Linear RGB in [0, 1].
glm::vec3 SkyColor(glm::vec3 direction, glm::vec3 sunDirection);

/// A camera that frames an axis-aligned box from the front-right, above (headless pictures, tests).
struct Camera {
  glm::vec3 eye, target, up{0, 1, 0};
  float fovYRadians = 0.8f;
  float nearPlane = 0.01f, farPlane = 100.0f;
  glm::mat4 View() const;
  glm::mat4 Projection(float aspect) const;
};
Camera FrameBox(const sim::Aabb& box, float aspect);

}  // namespace sphxr::render
