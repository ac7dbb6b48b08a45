#pragma once
// The desktop window (`sphxr --desktop`): a GLFW window with an orbit camera, the renderer, a Dear
// ImGui panel, and a mouse-driven hand. The simulation runs on a worker thread (app/src/sim_worker.h);
// the frame loop never waits on it.
#include <array>
#include <memory>
#include <string>

#include "sphxr/app/headless.h"
#include "sphxr/common/status.h"
#include "sphxr/render/gl_context.h"

namespace sphxr::app {

/// Where the mouse-driven hand wants to be, in world coordinates. Until the paddles land, nothing moves
/// in the water: the app draws the hand, and the lead wires this to sphxr::interaction::HandInput.
struct DesktopHand {
  bool active = false;                // a button is held over the scene
  std::array<float, 3> position{};    // m, target of the hand
  std::array<float, 3> velocity{};    // m/s, finite difference over the last frame
};

class DesktopApp {
 public:
  /// Opens the window (GL 4.5 core), the renderer, ImGui, and starts the simulation. One-line errors:
  /// no display, no GL 4.5, a bad scene.
  static Status Create(const Options& options, std::unique_ptr<DesktopApp>* out);
  ~DesktopApp();
  DesktopApp(const DesktopApp&) = delete;
  DesktopApp& operator=(const DesktopApp&) = delete;

  /// One frame: events, camera, draw the newest snapshot, the panel, swap. False once the window is closing.
  /// With `capture`, the finished frame (panel included) is read back before the swap.
  bool Frame(render::Image* capture = nullptr);
  /// Frames until the window closes (or `--frames-limit`).
  void Run();

  // Input, the same paths as GLFW's callbacks (tests script them). Coordinates in window pixels,
  // origin top-left as GLFW reports them.
  void OnMouseButton(int button, bool down);
  void OnCursor(double x, double y);
  void OnScroll(double dy);
  void OnKey(int key);

  const DesktopHand& Hand() const;
  bool Paused() const;
  int FramesDrawn() const;
  int PanelVertexCount() const;  // ImGui vertices of the last frame (0: the panel did not draw)
  int64_t SimSteps() const;      // of the newest snapshot
  bool ParticleMode() const;

 private:
  struct Impl;
  DesktopApp();
  std::unique_ptr<Impl> m_impl;
};

/// `sphxr --desktop`: runs the window until it closes. Fails (one line) when it cannot open one.
Status RunDesktop(const Options& options);

/// True when a display server is advertised (DISPLAY or WAYLAND_DISPLAY).
bool DisplayAvailable();

}  // namespace sphxr::app
