#include "sphxr/app/desktop.h"

// GL entry points from libepoxy; GLFW must not include its own GL header.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <thread>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <vector>

#include "gl_window.h"
#include "sphxr/app/param_registry.h"
#include "sim_worker.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/render/renderer.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::app {
namespace {

/// Orbit camera: yaw/pitch around a target, at a distance; pans move the target.
struct OrbitCamera {
  glm::vec3 target{0.0f};
  float yaw = 0.35f, pitch = 0.35f, distance = 1.0f;
  float fovY = 0.8f;
  glm::vec3 Eye() const {
    return target + distance * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
  }
  glm::mat4 View() const { return glm::lookAt(Eye(), target, glm::vec3(0, 1, 0)); }
  glm::mat4 Projection(float aspect) const {
    return glm::perspective(fovY, aspect, std::max(1e-3f, 0.01f * distance), 100.0f * distance);
  }
};

constexpr int kHistory = 180;  // frames of timing history in the graphs

}  // namespace

struct DesktopApp::Impl {
  Options options;
  SceneFile scene;
  sim::SceneSetup setup;  // what the panel edits (applied with a rebuild)
  GLFWwindow* window = nullptr;
  bool imguiReady = false;
  std::unique_ptr<render::Renderer> renderer;
  std::unique_ptr<SimWorker> worker;
  InteropSurface interop;  // the surface on the GPU path (written in place; unused on the CPU backend)
  OrbitCamera camera;
  render::RenderMode mode = render::RenderMode::kWater;
  render::ParticleColor color = render::ParticleColor::kSpeed;
  DesktopHand hand;
  glm::vec3 handPrevious{0.0f};
  SimScene simScene;         // the scene's paddles (with the mouse's) and surface
  std::shared_ptr<const StateFile> start;  // --load-state: where the scene of the command line starts
  float surfaceCell = 1.0f;  // surface cell size in particle spacings (panel)
  float panelHaptic = 0.0f;
  int64_t surfaceTriangles = 0;
  std::shared_ptr<const SimSnapshot> shown;
  bool dragHand = false, dragOrbit = false, dragPan = false;
  double cursorX = 0, cursorY = 0;
  int frames = 0;
  int panelVertices = 0;
  int64_t simSteps = 0;
  std::vector<std::string> sceneFiles;
  int sceneIndex = -1;
  std::deque<float> stageHistory[static_cast<int>(sim::Stage::kCount) + 2];  // + surface, render
  std::deque<float> fpsHistory;
  double renderMs = 0.0;
  std::chrono::steady_clock::time_point lastFrame = std::chrono::steady_clock::now();
  float frameSeconds = 1.0f / 60.0f;

  ~Impl() {
    if (worker) worker->Stop();
    worker.reset();
    if (window) glfwMakeContextCurrent(window);
    interop.Reset();
    renderer.reset();
    CloseGlWindow(window, imguiReady);
  }

  void FrameTank() {
    const sim::Aabb& t = setup.tank;
    const glm::vec3 lo(t.min.x, t.min.y, t.min.z), hi(t.max.x, t.max.y, t.max.z);
    camera.target = 0.5f * (lo + hi);
    camera.distance = 1.3f * 0.5f * glm::length(hi - lo) / std::sin(0.5f * camera.fovY);
    camera.yaw = 0.35f;
    camera.pitch = 0.35f;
  }

  /// World ray through a window pixel (GLFW coordinates: origin top-left, in screen units).
  void Ray(double x, double y, glm::vec3* origin, glm::vec3* dir) const {
    int w = 1, h = 1;
    glfwGetWindowSize(window, &w, &h);
    const float aspect = static_cast<float>(std::max(w, 1)) / static_cast<float>(std::max(h, 1));
    const glm::mat4 inv = glm::inverse(camera.Projection(aspect) * camera.View());
    const glm::vec2 ndc(2.0f * static_cast<float>(x) / std::max(w, 1) - 1.0f, 1.0f - 2.0f * static_cast<float>(y) / std::max(h, 1));
    const glm::vec4 far = inv * glm::vec4(ndc, 1.0f, 1.0f);
    *origin = camera.Eye();
    *dir = glm::normalize(glm::vec3(far) / far.w - *origin);
  }

  /// The mouse's hand as the paddles read it: tracked while the left button is held; the grip placed so
  /// that the blade's centre is at the mouse's point, the blade's face turned across the screen (a drag
  /// to the side pushes the water with the face, not the edge).
  std::vector<interaction::HandInput> HandInputs() const {
    std::vector<interaction::HandInput> hands(2);
    interaction::HandInput& h = hands[hand.index];
    if (!hand.active) return hands;
    const interaction::PaddleDesc* held = nullptr;
    for (const interaction::PaddleDesc& d : simScene.paddles) {
      if (d.holder == (hand.index == 0 ? interaction::Holder::kLeftHand : interaction::Holder::kRightHand)) held = &d;
    }
    if (!held) return hands;
    // The blade's thin axis (body x or z) is turned to the camera's horizontal right vector.
    const glm::mat4 view = camera.View();
    glm::vec3 right(view[0][0], 0.0f, view[2][0]);
    right = glm::length(right) > 1e-6f ? glm::normalize(right) : glm::vec3(1, 0, 0);
    bool thinX = false;
    for (const sim::ShapePrimitive& sp : held->shapes) {
      if (sp.kind == sim::ShapePrimitive::Kind::kBox) thinX = sp.b.x < sp.b.z;
    }
    const float theta = thinX ? std::atan2(-right.z, right.x) : std::atan2(right.x, right.z);
    const glm::quat q = glm::angleAxis(theta, glm::vec3(0, 1, 0));
    const sim::Vec3 w = PaddleWorkingPoint(held->shapes);
    const glm::vec3 grip = glm::vec3(hand.position[0], hand.position[1], hand.position[2]) - q * glm::vec3(w.x, w.y, w.z);
    h.tracked = true;
    h.pose.position = {grip.x, grip.y, grip.z};
    h.pose.orientation = {q.w, q.x, q.y, q.z};
    return hands;
  }

  /// The hand's target: the mouse ray meets the plane through the tank's centre that faces the camera,
  /// clamped to the tank (a hand stays within reach of the water).
  void UpdateHand(bool moved) {
    if (!dragHand) {
      hand.active = false;
      hand.velocity = {0, 0, 0};
      return;
    }
    glm::vec3 o, d;
    Ray(cursorX, cursorY, &o, &d);
    const glm::vec3 n = glm::normalize(camera.target - camera.Eye());
    const float denom = glm::dot(d, n);
    if (std::abs(denom) < 1e-6f) return;
    const float t = glm::dot(camera.target - o, n) / denom;
    glm::vec3 p = o + d * std::max(t, 0.0f);
    const sim::Aabb& tank = setup.tank;
    p = glm::clamp(p, glm::vec3(tank.min.x, tank.min.y, tank.min.z), glm::vec3(tank.max.x, tank.max.y, tank.max.z));
    const glm::vec3 v = hand.active ? (p - handPrevious) / std::max(frameSeconds, 1e-4f) : glm::vec3(0.0f);
    (void)moved;
    hand.active = true;
    hand.position = {p.x, p.y, p.z};
    hand.velocity = {v.x, v.y, v.z};
    handPrevious = p;
  }

  void Rebuild() {
    worker->Reset(setup);
  }

  /// The scene's paddles, and a default paddle for the mouse's hand when no paddle of the scene is
  /// held by a hand (the mouse then plays the first hand-held paddle's hand).
  void MakeSimScene() {
    simScene = SimSceneFromFile(scene);
    simScene.setup = setup;
    simScene.start = start;
    hand.index = 1;
    bool handHeld = false;
    for (const interaction::PaddleDesc& d : simScene.paddles) {
      if (!handHeld && d.holder != interaction::Holder::kScript) {
        handHeld = true;
        hand.index = d.holder == interaction::Holder::kLeftHand ? 0 : 1;
      }
    }
    if (!handHeld) simScene.paddles.push_back(DefaultHandPaddle(setup, hand.index));
    const float spacing = setup.params.spacing;
    surfaceCell = simScene.surface.params.cellSize > 0.0f && spacing > 0.0f ? simScene.surface.params.cellSize / spacing : 1.0f;
    simScene.surface.params.cellSize = surfaceCell * spacing;
    simScene.surface.enabled = mode == render::RenderMode::kWater;
  }

  SurfaceRequest Surface() const {
    SurfaceRequest r = simScene.surface;
    r.enabled = mode == render::RenderMode::kWater;
    r.params.cellSize = surfaceCell * setup.params.spacing;
    return r;
  }

  void LoadSceneFile(const std::string& path) {
    SceneFile next;
    if (Status s = LoadScene(path, &next); !s) {
      SPHXR_LOG_WARN("%s", s.message().c_str());
      return;
    }
    scene = next;
    setup = scene.setup;
    start.reset();  // --load-state belongs to the scene of the command line
    MakeSimScene();
    worker->Reset(simScene);
    FrameTank();
  }

  void Panel(const SimSnapshot& snap);

  /// The s key and the panel's button: the running state into --save-state's file, else
  /// "<scene name>.state" in the working directory (docs/user/scenes.md "State files").
  void SaveState() { saveMessage = worker->SaveStateLogged(options.saveState, scene.name); }
  std::string saveMessage;  // the last save, shown in the panel
};

DesktopApp::DesktopApp() : m_impl(std::make_unique<Impl>()) {}
DesktopApp::~DesktopApp() = default;

bool DisplayAvailable() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

Status DesktopApp::Create(const Options& options, std::unique_ptr<DesktopApp>* out) {
  out->reset();
  if (!DisplayAvailable()) return Status::Error("no display (DISPLAY and WAYLAND_DISPLAY are not set)");
  std::unique_ptr<DesktopApp> app(new DesktopApp());
  Impl& m = *app->m_impl;
  m.options = options;
  {
    RunStart start;
    if (Status s = PrepareStart(options, &start); !s) return s;
    m.scene = std::move(start.scene);
    m.setup = start.setup;
    m.start = start.state;
  }

  render::RendererConfig config;
  config.debug = config.debug || options.glDebug;
  GlWindowRequest request;
  request.width = options.windowWidth;
  request.height = options.windowHeight;
  request.debug = config.debug;
  request.vsync = options.vsync;
  if (Status s = OpenGlWindow(request, &m.window); !s) return s;
  if (Status s = render::Renderer::Create(config, &m.renderer); !s) return s;
  SPHXR_LOG_INFO("desktop window %dx%d, %s", options.windowWidth, options.windowHeight, render::GlDescription());
  if (const std::string ignored = HeadlessOnlyOptions(options); !ignored.empty()) {
    SPHXR_LOG_WARN("%s: honoured by --headless runs only; the window ignores them", ignored.c_str());
  }

  // Our callbacks first: ImGui's backend chains to them after taking what it needs.
  glfwSetWindowUserPointer(m.window, app.get());
  glfwSetMouseButtonCallback(m.window, [](GLFWwindow* w, int button, int action, int) {
    auto* self = static_cast<DesktopApp*>(glfwGetWindowUserPointer(w));
    if (action == GLFW_PRESS && ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse) return;
    self->OnMouseButton(button, action == GLFW_PRESS);
  });
  glfwSetCursorPosCallback(m.window, [](GLFWwindow* w, double x, double y) {
    static_cast<DesktopApp*>(glfwGetWindowUserPointer(w))->OnCursor(x, y);
  });
  glfwSetScrollCallback(m.window, [](GLFWwindow* w, double, double dy) {
    if (ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse) return;
    static_cast<DesktopApp*>(glfwGetWindowUserPointer(w))->OnScroll(dy);
  });
  glfwSetKeyCallback(m.window, [](GLFWwindow* w, int key, int, int action, int) {
    if (action != GLFW_PRESS || (ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard)) return;
    static_cast<DesktopApp*>(glfwGetWindowUserPointer(w))->OnKey(key);
  });
  InitImGui(m.window);
  m.imguiReady = true;

  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(SPHXR_SCENES_DIR, ec)) {
    if (entry.path().extension() == ".json") m.sceneFiles.push_back(entry.path().string());
  }
  std::sort(m.sceneFiles.begin(), m.sceneFiles.end());
  for (size_t i = 0; i < m.sceneFiles.size(); ++i) {
    if (std::filesystem::equivalent(m.sceneFiles[i], options.scenePath, ec)) m.sceneIndex = static_cast<int>(i);
  }

  const sim::SolverConfig solverConfig = InteractiveSolverConfig(options, true);
  if (Status s = ApplyAutoQuality(options, options.quality != 0, m.start.get(), solverConfig, &m.setup); !s) return s;
  m.mode = options.particleImages ? render::RenderMode::kParticles : render::RenderMode::kWater;
  m.MakeSimScene();
  m.worker = std::make_unique<SimWorker>(solverConfig);
  if (Status s = m.worker->Start(m.simScene); !s) return Status::Error(options.scenePath + ": " + s.message());
  m.FrameTank();
  *out = std::move(app);
  return Status::Ok();
}

void DesktopApp::OnMouseButton(int button, bool down) {
  Impl& m = *m_impl;
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    m.dragHand = down;
    m.hand.active = false;
    m.UpdateHand(false);
  } else if (button == GLFW_MOUSE_BUTTON_RIGHT) {
    m.dragOrbit = down;
  } else if (button == GLFW_MOUSE_BUTTON_MIDDLE) {
    m.dragPan = down;
  }
}

void DesktopApp::OnCursor(double x, double y) {
  Impl& m = *m_impl;
  const double dx = x - m.cursorX, dy = y - m.cursorY;
  m.cursorX = x;
  m.cursorY = y;
  if (m.dragOrbit) {
    m.camera.yaw -= 0.006f * static_cast<float>(dx);
    m.camera.pitch = std::clamp(m.camera.pitch + 0.006f * static_cast<float>(dy), -1.5f, 1.5f);
  }
  if (m.dragPan) {
    const glm::mat4 view = m.camera.View();
    const glm::vec3 right(view[0][0], view[1][0], view[2][0]), up(view[0][1], view[1][1], view[2][1]);
    const float scale = 0.0015f * m.camera.distance;
    m.camera.target += (-static_cast<float>(dx) * right + static_cast<float>(dy) * up) * scale;
  }
  if (m.dragHand) m.UpdateHand(true);
}

void DesktopApp::OnScroll(double dy) {
  m_impl->camera.distance *= std::pow(0.9f, static_cast<float>(dy));
  m_impl->camera.distance = std::clamp(m_impl->camera.distance, 1e-3f, 1e3f);
}

void DesktopApp::OnKey(int key) {
  Impl& m = *m_impl;
  switch (key) {
    case GLFW_KEY_SPACE: m.worker->SetPaused(!m.worker->Paused()); break;
    case GLFW_KEY_N:
    case GLFW_KEY_PERIOD:
      m.worker->SetPaused(true);
      m.worker->StepOnce();
      break;
    case GLFW_KEY_R: m.Rebuild(); break;
    case GLFW_KEY_M:
      m.mode = m.mode == render::RenderMode::kWater ? render::RenderMode::kParticles : render::RenderMode::kWater;
      break;
    case GLFW_KEY_C: m.color = static_cast<render::ParticleColor>((static_cast<int>(m.color) + 1) % 3); break;
    case GLFW_KEY_F: m.FrameTank(); break;
    case GLFW_KEY_S: m.SaveState(); break;
    case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(m.window, GLFW_TRUE); break;
    default: break;
  }
}

const DesktopHand& DesktopApp::Hand() const { return m_impl->hand; }
std::shared_ptr<const SimSnapshot> DesktopApp::Snapshot() const { return m_impl->shown; }
float DesktopApp::PanelHaptic() const { return m_impl->panelHaptic; }
int64_t DesktopApp::SurfaceTriangles() const { return m_impl->surfaceTriangles; }
bool DesktopApp::Paused() const { return m_impl->worker->Paused(); }
int DesktopApp::FramesDrawn() const { return m_impl->frames; }
int DesktopApp::PanelVertexCount() const { return m_impl->panelVertices; }
int64_t DesktopApp::SimSteps() const { return m_impl->simSteps; }
bool DesktopApp::ParticleMode() const { return m_impl->mode == render::RenderMode::kParticles; }

void DesktopApp::Impl::Panel(const SimSnapshot& snap) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(260, 80), ImVec2(700, std::max(100.0f, ImGui::GetIO().DisplaySize.y - 20)));
  ImGui::Begin("sphxr");
  // Scene
  if (!sceneFiles.empty()) {
    const std::string current = sceneIndex >= 0 ? std::filesystem::path(sceneFiles[sceneIndex]).stem().string() : "(other)";
    if (ImGui::BeginCombo("scene", current.c_str())) {
      for (size_t i = 0; i < sceneFiles.size(); ++i) {
        if (ImGui::Selectable(std::filesystem::path(sceneFiles[i]).stem().string().c_str(), static_cast<int>(i) == sceneIndex)) {
          sceneIndex = static_cast<int>(i);
          LoadSceneFile(sceneFiles[i]);
        }
      }
      ImGui::EndCombo();
    }
  }
  if (ImGui::Button(worker->Paused() ? "run (space)" : "pause (space)")) worker->SetPaused(!worker->Paused());
  ImGui::SameLine();
  if (ImGui::Button("step (n)")) {
    worker->SetPaused(true);
    worker->StepOnce();
  }
  ImGui::SameLine();
  if (ImGui::Button("reset (r)")) Rebuild();
  ImGui::SameLine();
  if (ImGui::Button("save state (s)")) SaveState();
  if (!saveMessage.empty()) ImGui::TextWrapped("%s", saveMessage.c_str());
  const std::string error = worker->LastError();
  if (!error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", error.c_str());

  ImGui::Text("%d fluid + %d boundary particles", snap.fluidCount, snap.boundaryCount);
  ImGui::Text("t = %.3f s, step %lld, dt %.2e s", snap.last.time, static_cast<long long>(snap.steps), snap.last.dt);
  ImGui::Text("simulation %.1f steps/s, %.3g simulated s per wall s", snap.stepsPerSecond, snap.simSecondsPerWallSecond);
  // The worker never runs ahead of wall time; when it falls behind, the water is shown slower than real.
  if (snap.simSecondsPerWallSecond > 0.0 && snap.simSecondsPerWallSecond < 0.95) {
    ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "x%.2f real time (this machine cannot keep up)",
                       snap.simSecondsPerWallSecond);
  }
  ImGui::Text("display %.1f fps, render %.2f ms", ImGui::GetIO().Framerate, renderMs);

  // Timing graph per stage
  if (ImGui::CollapsingHeader("timing (ms per step / frame)", ImGuiTreeNodeFlags_DefaultOpen)) {
    for (int s = 0; s <= static_cast<int>(sim::Stage::kCount) + 1; ++s) {
      const std::deque<float>& h = stageHistory[s];
      std::vector<float> values(h.begin(), h.end());
      const int n = static_cast<int>(sim::Stage::kCount);
      const char* name = s < n ? sim::StageName(static_cast<sim::Stage>(s)) : s == n ? "surface" : "render";
      const float last = values.empty() ? 0.0f : values.back();
      const float top = values.empty() ? 1.0f : std::max(1e-3f, *std::max_element(values.begin(), values.end()));
      const std::string label = Format("%-9s %6.2f", name, last);
      ImGui::PlotLines(label.c_str(), values.data(), static_cast<int>(values.size()), 0, nullptr, 0.0f, top, ImVec2(180, 22));
    }
    if (mode == render::RenderMode::kWater) {
      ImGui::TextDisabled("surface: HPMC, %lld triangles, cell %.4f m, %.2f ms per extraction",
                          static_cast<long long>(snap.SurfaceTriangles()), snap.surfaceCellSize, snap.surfaceMs);
    } else {
      ImGui::TextDisabled("surface: not extracted in particle mode");
    }
  }

  // Paddles: where they are, what the water does to them, what a hand would feel.
  if (ImGui::CollapsingHeader("paddles", ImGuiTreeNodeFlags_DefaultOpen)) {
    for (size_t k = 0; k < snap.paddles.size(); ++k) {
      const PaddlePose& p = snap.paddles[k];
      const char* who = p.hand == 0 ? "left hand" : p.hand == 1 ? "right hand" : "script";
      ImGui::Text("%s%s: %s, fluid force %.3f N", who, p.hand == hand.index ? " (mouse)" : "",
                  interaction::PaddleModeName(p.mode), sim::Length(p.force));
    }
    panelHaptic = snap.haptic[hand.index];
    ImGui::ProgressBar(panelHaptic, ImVec2(180, 0), Format("%.2f", panelHaptic).c_str());
    ImGui::SameLine();
    ImGui::Text("haptic (%s)", hand.index == 0 ? "left" : "right");
  }
  // Parameters: the one registry (app/src/param_registry.h) that scene files and --set read too.
  auto editor = [&](const ParamDesc& p) {
    bool edited = false;
    if (p.integer) {
      int v = static_cast<int>(p.Get(setup));
      ImGui::DragInt(p.name.c_str(), &v, 0.2f, static_cast<int>(p.min), static_cast<int>(p.max), "%d",
                     ImGuiSliderFlags_AlwaysClamp);
      if (ImGui::IsItemDeactivatedAfterEdit() || (ImGui::IsItemEdited() && !ImGui::IsItemActive())) edited = true;
      if (ImGui::IsItemEdited()) p.Set(&setup, v);
    } else {
      float v = static_cast<float>(p.Get(setup));
      const float lo = static_cast<float>(p.min), hi = static_cast<float>(p.max);
      if (p.name == "spacing") {
        // A spacing that would make millions of particles is refused by the solver with a message.
        ImGui::SliderFloat("spacing (m)", &v, std::max(lo, 5e-4f), std::min(hi, 0.05f), "%.4f",
                           ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
      } else {
        ImGui::DragFloat(p.name.c_str(), &v, 0.005f * std::max(std::abs(v), 0.1f), lo, hi, "%.4g",
                         ImGuiSliderFlags_AlwaysClamp);
      }
      if (ImGui::IsItemEdited()) p.Set(&setup, v);
      edited = ImGui::IsItemDeactivatedAfterEdit();
    }
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("%s\nrange %g to %g %s, default %g", p.help.c_str(), p.min, p.max, p.unit.c_str(), p.defaultValue);
    }
    return edited;
  };
  if (ImGui::CollapsingHeader("solver (edits rebuild the scene)")) {
    // The pressure solver by name, as the scene's solver.method (docs/design/dfsph.md).
    for (sim::SolverMethod m : {sim::SolverMethod::kWcsph, sim::SolverMethod::kDfsph}) {
      if (m != sim::SolverMethod::kWcsph) ImGui::SameLine();
      if (ImGui::RadioButton(sim::SolverMethodName(m), setup.method == m) && setup.method != m) {
        setup.method = m;
        Rebuild();
      }
    }
    if (setup.method == sim::SolverMethod::kDfsph) {
      ImGui::Text("last step: %d density, %d divergence iterations; errors %.3g %%, %.3g %%",
                  snap.last.densityIterations, snap.last.divergenceIterations, 100.0 * snap.last.solverDensityError,
                  100.0 * snap.last.solverDivergenceError);
    }
    for (const ParamDesc& p : ParamRegistry()) {
      if (p.group == "solver" && editor(p)) Rebuild();
    }
  }
  if (ImGui::CollapsingHeader("activity-based reuse", ImGuiTreeNodeFlags_DefaultOpen)) {
    sim::ReuseParams& r = setup.reuse;
    if (ImGui::Checkbox("reuse on", &r.enabled)) Rebuild();
    ImGui::SameLine();
    ImGui::Text("active fraction %.1f %%", 100.0 * snap.last.activeFraction);
    ImGui::TextUnformatted("preset:");
    for (const char* preset : {"accurate", "balanced", "fast"}) {
      ImGui::SameLine();
      if (ImGui::SmallButton(preset) && sim::ApplyReusePreset(preset, &r)) Rebuild();  // turns reuse on
    }
    for (const ParamDesc& p : ParamRegistry()) {
      if (p.group == "reuse" && editor(p) && r.enabled) Rebuild();
    }
  }
  // Rendering
  if (ImGui::CollapsingHeader("render", ImGuiTreeNodeFlags_DefaultOpen)) {
    int m = static_cast<int>(mode);
    ImGui::RadioButton("water", &m, 0);
    ImGui::SameLine();
    ImGui::RadioButton("particles (m)", &m, 1);
    mode = static_cast<render::RenderMode>(m);
    int c = static_cast<int>(color);
    ImGui::Combo("colour (c)", &c, "speed\0density error\0reuse activity\0");
    color = static_cast<render::ParticleColor>(c);
    ImGui::SliderFloat("surface cell (spacings)", &surfaceCell, 0.5f, 2.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("edge of a marching-cubes cell of the water surface, in particle spacings (%.4f m);\n"
                        "finer is smoother and slower (the scene's surface.cell_size sets the start)",
                        surfaceCell * setup.params.spacing);
    }
  }
  ImGui::TextDisabled("left drag: paddle  right drag: orbit  middle drag: pan  wheel: zoom  f: frame");
  if (hand.active) {
    ImGui::Text("hand target [%.3f %.3f %.3f] m, speed %.2f m/s", hand.position[0], hand.position[1], hand.position[2],
                std::sqrt(hand.velocity[0] * hand.velocity[0] + hand.velocity[1] * hand.velocity[1] +
                          hand.velocity[2] * hand.velocity[2]));
  }
  ImGui::End();
}

bool DesktopApp::Frame(render::Image* capture) {
  Impl& m = *m_impl;
  if (glfwWindowShouldClose(m.window)) return false;
  glfwPollEvents();
  const auto now = std::chrono::steady_clock::now();
  m.frameSeconds = std::chrono::duration<float>(now - m.lastFrame).count();
  m.lastFrame = now;

  // The newest snapshot: drawn again with the newest camera when the simulation has not published.
  m.worker->SetHands(m.HandInputs());
  m.worker->SetSurface(m.Surface());
  const std::shared_ptr<const SimSnapshot> snap = m.worker->Latest();
  m.shown = snap;
  m.simSteps = snap->steps;
  auto push = [](std::deque<float>& h, float v) {
    h.push_back(v);
    while (h.size() > kHistory) h.pop_front();
  };
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) push(m.stageHistory[s], static_cast<float>(snap->stageMs[s]));
  push(m.stageHistory[static_cast<int>(sim::Stage::kCount)], static_cast<float>(snap->surfaceMs));
  push(m.stageHistory[static_cast<int>(sim::Stage::kCount) + 1], static_cast<float>(m.renderMs));

  int fbw = 0, fbh = 0;
  glfwGetFramebufferSize(m.window, &fbw, &fbh);
  // GPU path: the snapshot's mesh is still in the solver; it is written into the GL buffers here (once per build).
  const render::InteropMesh* deviceSurface = m.interop.Update(*m.worker, *snap);
  const render::FrameScene frame = MakeFrameScene(*snap, m.mode, m.color, deviceSurface);
  m.surfaceTriangles = (frame.deviceSurface ? frame.deviceSurface->VertexCount() : frame.surface.vertexCount) / 3;
  const auto t0 = std::chrono::steady_clock::now();
  if (fbw > 0 && fbh > 0) {
    render::View view;
    view.view = m.camera.View();
    view.projection = m.camera.Projection(static_cast<float>(fbw) / static_cast<float>(fbh));
    view.framebuffer = 0;
    view.width = fbw;
    view.height = fbh;
    m.renderer->Draw(frame, std::span(&view, 1));
  }
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  m.Panel(*snap);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  m.panelVertices = ImGui::GetDrawData() ? ImGui::GetDrawData()->TotalVtxCount : 0;
  if (capture && fbw > 0 && fbh > 0) *capture = render::ReadPixels(0, 0, 0, fbw, fbh);
  m.renderMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  glfwSwapBuffers(m.window);
  ++m.frames;
  return true;
}

void DesktopApp::Run() {
  const int limit = m_impl->options.frameLimit;
  const std::string& shot = m_impl->options.screenshotPath;
  render::Image last;
  // With --screenshot, every frame is read back so the one before closing can be written (slower).
  while (Frame(shot.empty() ? nullptr : &last)) {
    if (limit > 0 && m_impl->frames >= limit) break;
  }
  if (!shot.empty() && last.width > 0) {
    if (Status s = WritePng(shot, last); !s) {
      SPHXR_LOG_WARN("%s", s.message().c_str());
    } else {
      SPHXR_LOG_INFO("window picture: %s (%dx%d)", shot.c_str(), last.width, last.height);
    }
  }
}

Status RunDesktop(const Options& options) {
  std::unique_ptr<DesktopApp> app;
  if (Status s = DesktopApp::Create(options, &app); !s) return s;
  app->Run();
  return Status::Ok();
}

}  // namespace sphxr::app
