#include "sphxr/app/xr_mode.h"

// GL entry points from libepoxy; GLFW must not include its own GL header.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <memory>
#include <span>
#include <thread>
#include <vector>

#include "gl_window.h"
#include "interrupt_scope.h"
#include "interop_surface.h"
#include "sim_worker.h"
#include "xr_hands.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/display.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/interaction/hand.h"
#include "sphxr/render/renderer.h"
#include "sphxr/app/render_budget.h"
#include "sphxr/xr/session.h"

// From glfw3native.h (which would also pull in Xlib.h and its macros): the X display GLFW opened.
extern "C" struct _XDisplay* glfwGetX11Display(void);

namespace sphxr::app {
namespace {

using Clock = std::chrono::steady_clock;

glm::mat4 ToGlm(const xr::Mat4& m) { return glm::make_mat4(m.m.data()); }

double MeanSpeed(const sim::HostFluid& fluid) {
  double sum = 0.0;
  for (const sim::Vec4& v : fluid.velocity) sum += std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return fluid.velocity.empty() ? 0.0 : sum / static_cast<double>(fluid.velocity.size());
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

/// Everything an XR run owns, destroyed in the order GL needs (the session's GL objects first, with
/// the context current; the window last).
struct XrApp {
  Options options;
  SceneFile scene;
  sim::SceneSetup setup;  // the scene at the spacing in use
  SimScene simScene;      // with a paddle for each hand; what reset restores
  std::shared_ptr<const StateFile> start;  // --load-state
  sim::Vec3 offset;       // play = sim + offset
  GLFWwindow* window = nullptr;
  bool imguiReady = false;
  std::unique_ptr<render::Renderer> renderer;
  std::unique_ptr<RenderBudget> budget;  // the render quality, lowered under --quality auto when frames do not fit
  FrameStatsCsv frameStats;              // --frame-stats
  std::unique_ptr<xr::Session> session;
  std::unique_ptr<SimWorker> worker;
  InteropSurface interop;  // the surface on the GPU path (written in place; unused on the CPU backend)
  render::RenderMode mode = render::RenderMode::kWater;
  render::ParticleColor color = render::ParticleColor::kSpeed;
  float lastHaptic[xr::kHandCount] = {0, 0};
  // A finished save is felt: the right controller buzzes (kSaveBuzz) for kSaveBuzzSeconds, since the
  // person in the headset cannot see the mirror panel's message. A failed save is not (logged).
  static constexpr float kSaveBuzz = 0.8f;
  static constexpr double kSaveBuzzSeconds = 0.15;
  uint64_t savesFelt = 0;
  Clock::time_point buzzUntil{};
  bool exitRequested = false;

  ~XrApp() {
    if (worker) worker->Stop();
    if (window) glfwMakeContextCurrent(window);
    session.reset();
    interop.Reset();
    renderer.reset();
    CloseGlWindow(window, imguiReady);
  }

  void Panel(const SimSnapshot& snap, const XrOutcome& out) {
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(330, 0), ImGuiCond_FirstUseEver);
    ImGui::Begin("sphxr --xr");
    ImGui::Text("%s, %dx%d per eye", session->runtimeName().c_str(), session->eyeWidth(), session->eyeHeight());
    ImGui::Text("%s", xr::SessionStateName(session->state()));
    if (ImGui::Button(worker->Paused() ? "run" : "pause")) worker->SetPaused(!worker->Paused());
    ImGui::SameLine();
    if (ImGui::Button("reset")) worker->Reset(simScene);
    ImGui::SameLine();
    if (ImGui::Button("end session")) RequestExit();
    if (ImGui::Button("save state")) worker->RequestSave(options.saveState, scene.name);
    if (const std::string saved = worker->SaveMessage(); !saved.empty()) ImGui::TextWrapped("%s", saved.c_str());
    ImGui::Text("%d fluid + %d boundary particles", snap.fluidCount, snap.boundaryCount);
    ImGui::Text("t = %.3f s, %.3g simulated s per wall s", snap.last.time, snap.simSecondsPerWallSecond);
    if (snap.simSecondsPerWallSecond > 0.0 && snap.simSecondsPerWallSecond < 0.95) {
      ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "x%.2f real time", snap.simSecondsPerWallSecond);
    }
    const xr::FrameTimings& t = session->lastFrameTimings();
    ImGui::Text("frame %lld: wait %.2f, update %.2f, eyes %.2f ms", static_cast<long long>(out.frames), t.waitMs,
                t.updateMs, t.renderMs);
    int m = static_cast<int>(mode);
    ImGui::RadioButton("water", &m, 0);
    ImGui::SameLine();
    ImGui::RadioButton("particles", &m, 1);
    if (m != static_cast<int>(mode)) {
      mode = static_cast<render::RenderMode>(m);
      SurfaceRequest surface = simScene.surface;
      surface.enabled = mode == render::RenderMode::kWater;  // no surface extraction for particles
      worker->SetSurface(surface);
    }
    if (!snap.probes.empty() && ImGui::CollapsingHeader("probes (last 5 s)", ImGuiTreeNodeFlags_DefaultOpen)) {
      DrawProbePlots(snap.probes, 160.0f);
    }
    const std::string error = worker->LastError();
    if (!error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", error.c_str());
    ImGui::End();
  }

  void RequestExit() {
    if (exitRequested) return;
    exitRequested = true;
    if (Status s = session->RequestExit(); !s) SPHXR_LOG_WARN("%s", s.message().c_str());
  }

  /// The left eye's image, fitted into the window (aspect kept), while the image is still ours.
  void Mirror(const xr::EyeView& eye) {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    if (w <= 0 || h <= 0) return;
    const float scale = std::min(static_cast<float>(w) / eye.width, static_cast<float>(h) / eye.height);
    const int dw = static_cast<int>(eye.width * scale), dh = static_cast<int>(eye.height * scale);
    const int dx = (w - dw) / 2, dy = (h - dh) / 2;
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glDisable(GL_SCISSOR_TEST);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, eye.framebuffer);
    glBlitFramebuffer(eye.x, eye.y, eye.x + eye.width, eye.y + eye.height, dx, dy, dx + dw, dy + dh,
                      GL_COLOR_BUFFER_BIT, GL_LINEAR);
    glBindFramebuffer(GL_FRAMEBUFFER, eye.framebuffer);  // xr restores its own binding after
  }
};

/// After a displayed frame: its row of --frame-stats, and the render budget's judgement.
void FrameEnded(XrApp& app, int64_t frame, double intervalMs, double periodMs) {
  if (app.frameStats.IsOpen()) {
    if (Status s = app.frameStats.Append(frame, intervalMs, app.budget->Quality(), app.renderer->LastStats()); !s) {
      SPHXR_LOG_WARN("%s", s.message().c_str());
    }
  }
  if (app.budget->Observe(intervalMs, periodMs)) {
    app.renderer->SetQuality(app.budget->Quality());
    SPHXR_LOG_INFO("%s", app.budget->Why().c_str());
  }
}

Status OpenWindowAndSession(XrApp& app, XrOutcome* outcome) {
  const Options& options = app.options;
  render::RendererConfig config;
  config.debug = config.debug || options.glDebug;
  render::ParseRenderQuality(options.renderQuality, &config.quality);
  app.budget = std::make_unique<RenderBudget>(config.quality, options.quality != 0);
  if (!options.frameStatsPath.empty()) {
    if (Status s = app.frameStats.Open(options.frameStatsPath); !s) return s;
  }
  GlWindowRequest request;
  request.width = options.windowWidth;
  request.height = options.windowHeight;
  request.title = "sphxr (headset mirror: left eye)";
  request.what = "the headset's mirror window";
  request.debug = config.debug;
  request.vsync = false;  // the headset paces the loop, not the mirror
  if (Status s = OpenGlWindow(request, &app.window); !s) return s;
  if (Status s = render::Renderer::Create(config, &app.renderer); !s) return s;

  xr::GraphicsBinding binding;
  binding.getProcAddress = [](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); };
  if (Status s = xr::CurrentXlibGlxBinding(glfwGetX11Display(), &binding); !s) return s;
  if (Status s = xr::Session::Create({}, binding, &app.session); !s) return s;
  outcome->started = true;
  SPHXR_LOG_INFO("headset: runtime '%s', %dx%d per eye, %s", app.session->runtimeName().c_str(),
                 app.session->eyeWidth(), app.session->eyeHeight(), render::GlDescription());

  InitImGui(app.window);
  app.imguiReady = true;
  return Status::Ok();
}

Status StartSimulation(XrApp& app) {
  const Options& options = app.options;
  const sim::SolverConfig solverConfig = InteractiveSolverConfig(options, false);
  if (Status s = ApplyAutoQuality(options, options.quality != 0, app.start.get(), solverConfig, &app.setup); !s) return s;
  // Each controller holds a paddle: the scene's hand-held ones, else the default blade on a handle
  // (sized at the spacing in use).
  SceneFile atSpacing = app.scene;
  atSpacing.setup = app.setup;
  app.simScene = SimSceneFromFile(atSpacing, {0, 1});
  app.simScene.start = app.start;
  app.simScene.surface.enabled = app.mode == render::RenderMode::kWater;
  app.worker = std::make_unique<SimWorker>(solverConfig);
  if (Status s = app.worker->Start(app.simScene); !s) return Status::Error(options.scenePath + ": " + s.message());
  return Status::Ok();
}

// Before the headset: the scene and the state file (a bad one is one line before the session starts),
// the display, the runtime, the window and the session (an error there is the headset's: fall back),
// then the simulation.
Status PrepareXr(const Options& options, XrApp& app, XrOutcome* outcome) {
  app.options = options;
  {
    RunStart start;
    if (Status s = PrepareStart(options, &start); !s) return s;
    app.scene = std::move(start.scene);
    app.setup = start.setup;
    app.start = start.state;
  }
  app.offset = XrSceneOffset(app.setup.tank);
  app.mode = options.particleImages ? render::RenderMode::kParticles : render::RenderMode::kWater;

  if (!DisplayAvailable()) {
    outcome->fallback = true;
    return Status::Error("the headset needs a display for its mirror window and GL context (DISPLAY is not set)");
  }
  if (Status s = xr::ProbeRuntime(); !s) {  // before a window opens for nothing
    outcome->fallback = true;
    return s;
  }
  if (Status s = OpenWindowAndSession(app, outcome); !s) {
    outcome->fallback = true;
    return s;
  }
  if (const std::string ignored = HeadlessOnlyOptions(options); !ignored.empty()) {
    SPHXR_LOG_WARN("%s: honoured by --headless runs only; the headset session ignores them", ignored.c_str());
  }
  return StartSimulation(app);
}

/// The headset's frame loop: each pass polls the window and the session and, while the session runs,
/// makes one frame (the update with the newest snapshot, then each eye). It keeps the frame measures
/// and the last mirror image for the end of the run.
struct FrameLoop {
  XrApp& app;
  XrOutcome* outcome;
  glm::mat4 sceneToPlay;
  std::vector<double> intervals{}, busy{};  // ms between frames; ms of a frame outside xrWaitFrame
  std::shared_ptr<const SimSnapshot> previousSnap{};
  render::Image lastMirror{};  // --screenshot: the window's last mirror image
  Clock::time_point previousFrame{};
  int64_t previousPeriodNs = 0;
  Clock::time_point interruptedAt{};

  /// One pass: false once the session has ended (or is left, as a lost one is).
  bool Pass() {
    glfwPollEvents();
    const Options& options = app.options;
    if (glfwWindowShouldClose(app.window) || (options.frameLimit > 0 && outcome->frames >= options.frameLimit)) {
      app.RequestExit();
    }
    if (g_interrupt && !outcome->interrupted) {
      outcome->interrupted = g_interrupt;
      interruptedAt = Clock::now();
      SPHXR_LOG_INFO("%s: ending the headset session", InterruptName(outcome->interrupted));
      app.RequestExit();
    }
    // A session that does not end within two seconds of the signal (not running, a runtime that never
    // answers the request) is left as a lost one is.
    if (outcome->interrupted && Clock::now() - interruptedAt > std::chrono::seconds(2)) return false;
    const xr::EventResult ev = app.session->PollEvents();
    for (xr::SessionState state : ev.transitions) {
      if (!outcome->states.empty()) outcome->states += ' ';
      outcome->states += xr::SessionStateName(state);  // (appended, not a + b: GCC 12's -Wrestrict misfired there)
    }
    if (ev.exit) {
      outcome->lost = ev.lost;
      outcome->message = ev.message;
      return false;
    }
    if (!ev.running) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      return true;
    }
    return Frame();
  }

  /// One frame of the session; false when it failed.
  bool Frame() {
    // The newest snapshot: drawn again when the simulation has not published since the last frame.
    const std::shared_ptr<const SimSnapshot> snap = app.worker->Latest();
    if (snap != previousSnap) {  // how much the water moves (the tests compare a stirred tank with a still one)
      outcome->peakMeanFluidSpeed = std::max(outcome->peakMeanFluidSpeed, MeanSpeed(snap->fluid));
      previousSnap = snap;
    }
    render::FrameScene frame;
    bool mirrored = false;
    const Status f = app.session->Frame([&](const xr::FrameInfo& info) { Update(info, *snap, &frame); },
                                        [&](const xr::FrameInfo&, const xr::EyeView& eye) {
                                          if (Eye(frame, eye)) mirrored = true;
                                        });
    if (!f) {
      // A failing frame call is a lost session in all but name: end it the same way.
      SPHXR_LOG_WARN("%s", f.message().c_str());
      outcome->lost = true;
      outcome->message = f.message();
      return false;
    }
    const xr::FrameTimings& t = app.session->lastFrameTimings();
    busy.push_back(t.syncMs + t.updateMs + t.renderMs + t.endMs);
    if (mirrored) PanelOnMirror(*snap);
    return true;
  }

  /// The frame's update: its timing, the hands to the simulation, the haptics, the buttons, the scene.
  void Update(const xr::FrameInfo& info, const SimSnapshot& snap, render::FrameScene* frame) {
    ++outcome->frames;
    const Clock::time_point now = Clock::now();
    if (previousFrame != Clock::time_point{}) {
      const double ms = std::chrono::duration<double, std::milli>(now - previousFrame).count();
      intervals.push_back(ms);
      if (previousPeriodNs > 0 && ms > 1.5e-6 * static_cast<double>(previousPeriodNs)) ++outcome->lateFrames;
    }
    if (!intervals.empty()) FrameEnded(app, outcome->frames - 1, intervals.back(), 1e-6 * static_cast<double>(info.displayPeriodNs));
    previousFrame = now;
    previousPeriodNs = info.displayPeriodNs;

    const double displayTime = 1e-9 * static_cast<double>(info.predictedDisplayTimeNs);
    std::vector<interaction::HandInput> hands;
    for (int h = 0; h < xr::kHandCount; ++h) hands.push_back(ToHandInput(info.hands[size_t(h)], app.offset, app.setup.tank, displayTime));
    app.worker->SetHands(hands);
    if (info.displayPeriodNs > 0) app.worker->SetFrameRate(1e9 / static_cast<double>(info.displayPeriodNs));
    Haptics(snap, now);
    if (info.resetRequested) {
      SPHXR_LOG_INFO("reset button: the scene starts again");
      app.worker->Reset(app.simScene);
    }
    if (info.saveRequested) {  // the worker saves between two steps: the frame does not wait for it
      SPHXR_LOG_INFO("save button: saving the water");
      app.worker->RequestSave(app.options.saveState, app.scene.name);
    }
    // GPU path: the snapshot's mesh is written into the GL buffers here (once per build), before the eyes.
    *frame = MakeFrameScene(snap, app.mode, app.color, app.interop.Update(*app.worker, snap));
    DrawHandsAndPaddles(info, hands, app.offset, snap, frame);
    frame->frameKey = info.frameIndex + 1;  // both eyes share one upload and one shadow pass
  }

  /// Each hand's paddle felt in its controller, and a finished save felt in the right one.
  void Haptics(const SimSnapshot& snap, Clock::time_point now) {
    if (const uint64_t saves = app.worker->SavesDone(); saves != app.savesFelt) {
      app.savesFelt = saves;
      app.buzzUntil = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(XrApp::kSaveBuzzSeconds));
    }
    for (int h = 0; h < xr::kHandCount; ++h) {
      float amplitude = snap.haptic[h];
      if (amplitude < 0.01f) amplitude = 0.0f;
      if (h == static_cast<int>(xr::Hand::kRight) && now < app.buzzUntil) amplitude = std::max(amplitude, XrApp::kSaveBuzz);
      if (amplitude == 0.0f && app.lastHaptic[h] == 0.0f) continue;  // stop once, not every frame
      app.lastHaptic[h] = amplitude;
      if (Status hs = app.session->ApplyHaptics(static_cast<xr::Hand>(h), amplitude); !hs) {
        LogOnce("xr-haptics", LogLevel::kWarn, "%s", hs.message().c_str());
      }
    }
  }

  /// One eye's view drawn; the left eye is also mirrored into the window. True for the mirrored eye.
  bool Eye(const render::FrameScene& frame, const xr::EyeView& eye) {
    // The renderer writes display-ready colour (the desktop window shows its bytes as they are):
    // no second sRGB encoding, so the headset looks like the desktop window.
    glDisable(GL_FRAMEBUFFER_SRGB);
    render::View view;
    view.view = ToGlm(eye.view) * sceneToPlay;
    view.projection = ToGlm(eye.projection);
    view.framebuffer = eye.framebuffer;
    view.x = eye.x;
    view.y = eye.y;
    view.width = eye.width;
    view.height = eye.height;
    app.renderer->Draw(frame, std::span(&view, 1));
    if (eye.eye != 0) return false;
    app.Mirror(eye);
    if (!app.options.screenshotPath.empty()) {  // the mirror as blitted, before the panel
      int w = 0, h = 0;
      glfwGetFramebufferSize(app.window, &w, &h);
      if (w > 0 && h > 0) lastMirror = render::ReadPixels(0, 0, 0, w, h);
      glBindFramebuffer(GL_FRAMEBUFFER, eye.framebuffer);
    }
    ++outcome->rendered;
    return true;
  }

  /// The panel over the mirrored eye, and the window's swap.
  void PanelOnMirror(const SimSnapshot& snap) {
    int w = 0, h = 0;
    glfwGetFramebufferSize(app.window, &w, &h);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, w, h);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    app.Panel(snap, *outcome);
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    glfwSwapBuffers(app.window);
  }
};

// A lost session must not lose the water stirred in it: saved (to --save-state's file, else
// "<scene>-lost.state", else that name in the temporary folder), and the window that takes over starts
// from it (main.cpp). A session ended by a signal is saved the same way.
void SaveLostWater(XrApp& app, XrOutcome* outcome) {
  const Options& options = app.options;
  if (outcome->interrupted) {
    outcome->message = std::string("ended by ") + InterruptName(outcome->interrupted);
  }
  if (!outcome->lost && !outcome->interrupted) return;
  std::vector<std::string> paths = {!options.saveState.empty() ? options.saveState : LostStatePath(app.scene.name)};
  if (options.saveState.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    paths.push_back((std::filesystem::path(tmp && *tmp ? tmp : "/tmp") / LostStatePath(app.scene.name)).string());
  }
  for (const std::string& path : paths) {
    const uint64_t before = app.worker->SavesDone();
    app.worker->SaveStateLogged(path, app.scene.name);
    if (app.worker->SavesDone() > before) {
      outcome->savedState = path;
      break;
    }
  }
}

// --screenshot: the last mirror image (the left eye, without the panel).
void WriteMirrorPicture(const std::string& path, const render::Image& lastMirror) {
  if (path.empty()) return;
  if (lastMirror.width == 0) {
    SPHXR_LOG_WARN("--screenshot %s: no frame was drawn, no picture", path.c_str());
  } else if (Status s = WritePng(path, lastMirror); !s) {
    SPHXR_LOG_WARN("%s", s.message().c_str());
  } else {
    SPHXR_LOG_INFO("mirror picture (the left eye, without the panel): %s (%dx%d)", path.c_str(), lastMirror.width,
                   lastMirror.height);
  }
}

// The run's measures into `outcome`, and its summary on stdout.
void Summarise(XrApp& app, const FrameLoop& loop, double seconds, XrOutcome* outcome) {
  outcome->frameMsP50 = Percentile(loop.intervals, 0.5);
  outcome->frameMsP90 = Percentile(loop.intervals, 0.9);
  outcome->busyMsP50 = Percentile(loop.busy, 0.5);
  outcome->busyMsP90 = Percentile(loop.busy, 0.9);
  const std::shared_ptr<const SimSnapshot> last = app.worker->Latest();
  outcome->meanFluidSpeed = MeanSpeed(last->fluid);
  outcome->peakMeanFluidSpeed = std::max(outcome->peakMeanFluidSpeed, outcome->meanFluidSpeed);
  std::printf("sphxr --xr: %s after %lld frames (%lld drawn) in %.1f s; frame interval p50 %.2f / p90 %.2f ms, "
              "busy (all but xrWaitFrame) p50 %.2f / p90 %.2f ms, %lld late; simulation at t = %.3f s, %lld steps, "
              "mean fluid speed %.4f m/s (peak %.4f); last snapshot: %.2f ms per step, surface %.2f ms\n",
              outcome->message.c_str(), static_cast<long long>(outcome->frames), static_cast<long long>(outcome->rendered),
              seconds, outcome->frameMsP50, outcome->frameMsP90, outcome->busyMsP50, outcome->busyMsP90,
              static_cast<long long>(outcome->lateFrames), last->last.time, static_cast<long long>(last->steps),
              outcome->meanFluidSpeed, outcome->peakMeanFluidSpeed, last->stepMs, last->surfaceMs);
  std::printf("sphxr --xr: session states %s\n", outcome->states.c_str());
  std::printf("sphxr --xr: %s\n", RenderSummary(app.budget->Quality(), app.renderer->LastStats()).c_str());
  std::fflush(stdout);
}

}  // namespace

sim::Vec3 XrSceneOffset(const sim::Aabb& tank, const XrPlacement& placement) {
  return {placement.centerX - 0.5f * (tank.min.x + tank.max.x), placement.centerY - 0.5f * (tank.min.y + tank.max.y),
          placement.centerZ - 0.5f * (tank.min.z + tank.max.z)};
}

bool XrRuntimeAvailable(std::string* why) {
  const Status s = xr::ProbeRuntime();
  if (!s && why) *why = s.message();
  return static_cast<bool>(s);
}

Status RunXr(const Options& options, XrOutcome* outcome) {
  *outcome = XrOutcome{};
  XrApp app;
  if (Status s = PrepareXr(options, app, outcome); !s) return s;
  const glm::mat4 sceneToPlay = glm::translate(glm::mat4(1.0f), glm::vec3(app.offset.x, app.offset.y, app.offset.z));
  FrameLoop loop{app, outcome, sceneToPlay};
  const auto started = Clock::now();
  InterruptScope interrupts;  // to the end: a signal while the water is saved does not cut the save
  while (loop.Pass()) {
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
  SaveLostWater(app, outcome);
  WriteMirrorPicture(options.screenshotPath, loop.lastMirror);
  Summarise(app, loop, seconds, outcome);
  return Status::Ok();
}

}  // namespace sphxr::app
