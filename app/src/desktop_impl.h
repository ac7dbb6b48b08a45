#pragma once
// The desktop window's state (DesktopApp::Impl), shared by desktop.cpp (the window, input, the frame
// loop) and desktop_panel.cpp (the ImGui panel).
// GL entry points from libepoxy; GLFW must not include its own GL header.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <vector>

#include "gl_window.h"
#include "interop_surface.h"
#include "sim_worker.h"
#include "sphxr/app/desktop.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/render_budget.h"
#include "sphxr/common/log.h"
#include "sphxr/render/renderer.h"

namespace sphxr::app {

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


struct DesktopApp::Impl {
  Options options;
  SceneFile scene;
  sim::SceneSetup setup;  // what the panel edits (applied with a rebuild)
  GLFWwindow* window = nullptr;
  bool imguiReady = false;
  std::unique_ptr<render::Renderer> renderer;
  std::unique_ptr<RenderBudget> budget;  // the render quality, lowered under --quality auto when frames do not fit
  FrameStatsCsv frameStats;              // --frame-stats
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

  /// After a displayed frame: its --frame-stats row and the render budget's judgement (a 60 Hz display).
  void FrameEnded(double intervalMs) {
    if (frameStats.IsOpen()) {
      if (Status s = frameStats.Append(frames - 1, intervalMs, budget->Quality(), renderer->LastStats()); !s) {
        SPHXR_LOG_WARN("%s", s.message().c_str());
      }
    }
    if (budget->Observe(intervalMs, 1e3 / 60.0)) {
      renderer->SetQuality(budget->Quality());
      SPHXR_LOG_INFO("%s", budget->Why().c_str());
    }
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
  // The panel's sections (desktop_panel.cpp).
  void PanelStatus(const SimSnapshot& snap);
  void PanelTiming(const SimSnapshot& snap);
  void PanelProbesAndPaddles(const SimSnapshot& snap);
  void PanelSolver(const SimSnapshot& snap);
  void PanelReuse(const SimSnapshot& snap);
  void PanelRender();

  /// The s key and the panel's button: the running state into --save-state's file, else
  /// "<scene name>.state" in the working directory (docs/user/scenes.md "State files").
  void SaveState() { saveMessage = worker->SaveStateLogged(options.saveState, scene.name); }
  std::string saveMessage;  // the last save, shown in the panel
};

}  // namespace sphxr::app
