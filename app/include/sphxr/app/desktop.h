#pragma once
// The desktop window (`sphxr --desktop`): a GLFW window with an orbit camera, the renderer, a Dear
// ImGui panel, and a mouse-driven hand. The simulation runs on a worker thread (app/src/sim_worker.h);
// the frame loop never waits on it.
#include <array>
#include <memory>
#include <string>

#include "sphxr/app/options.h"
#include "sphxr/common/status.h"
#include "sphxr/render/gl_context.h"

namespace sphxr::app {

/// The mouse-driven hand: while the left button is held, where the mouse puts the blade of the paddle
/// it holds (world coordinates). The window sends it to the simulation thread as an
/// interaction::HandInput (SimWorker::SetHands), which drives a real paddle (interaction::PaddleSystem).
struct DesktopHand {
  bool active = false;                // the left button is held over the scene: the hand is tracked
  std::array<float, 3> position{};    // m, target of the paddle's blade centre
  std::array<float, 3> velocity{};    // m/s, finite difference over the last frame
  int index = 1;                      // the hand the mouse plays (0 left, 1 right)
};

struct SimSnapshot;

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
  /// The snapshot drawn by the last frame (paddle poses, haptics, surface); null before the first frame.
  std::shared_ptr<const SimSnapshot> Snapshot() const;
  /// The haptic amplitude of the mouse's hand as the panel showed it in the last frame (0..1).
  float PanelHaptic() const;
  /// Surface triangles drawn by the last frame (0: no surface mesh, e.g. particle mode).
  int64_t SurfaceTriangles() const;
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

}  // namespace sphxr::app
