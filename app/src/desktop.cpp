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

#include "desktop_impl.h"
#include "gl_window.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/display.h"
#include "sphxr/app/param_registry.h"
#include "sim_worker.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/render/renderer.h"


namespace sphxr::app {

DesktopApp::DesktopApp() : m_impl(std::make_unique<Impl>()) {}
DesktopApp::~DesktopApp() = default;

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
  render::ParseRenderQuality(options.renderQuality, &config.quality);
  m.budget = std::make_unique<RenderBudget>(config.quality, options.quality != 0);
  if (!options.frameStatsPath.empty()) {
    if (Status s = m.frameStats.Open(options.frameStatsPath); !s) return s;
  }
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

  // The panel's scene list: the installed scenes, or the build's (the current directory's JSON files
  // need not be scenes).
  std::error_code ec;
  for (const std::string& dir : SceneSearchDirs()) {
    if (dir == ".") continue;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".json") m.sceneFiles.push_back(entry.path().string());
    }
    break;
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

bool DesktopApp::Frame(render::Image* capture) {
  Impl& m = *m_impl;
  if (glfwWindowShouldClose(m.window)) return false;
  glfwPollEvents();
  const auto now = std::chrono::steady_clock::now();
  m.frameSeconds = std::chrono::duration<float>(now - m.lastFrame).count();
  m.lastFrame = now;
  if (m.frames > 0) m.FrameEnded(1e3 * m.frameSeconds);

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
  m.surfaceTriangles = frame.deviceSurface ? snap->SurfaceTriangles() : frame.surface.vertexCount / 3;
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
