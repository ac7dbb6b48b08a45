#pragma once
// sphxr's OpenXR layer: instance, session, swapchains, actions and the frame loop, behind plain types.
// Nothing outside xr/ includes OpenXR headers; poses arrive as sphxr::xr::Pose in the application's
// play space (STAGE if the runtime has it, else LOCAL, shifted by Recentre()).
//
// The loop an application runs (the GL context of `GraphicsBinding` must be current on this thread):
//
//   std::unique_ptr<xr::Session> xr;
//   if (Status s = xr::Session::Create(options, binding, &xr); !s) { print s.message(); desktop mode }
//   while (true) {
//     xr::EventResult ev = xr->PollEvents();
//     if (ev.exit) break;                          // EXITING, session lost, instance lost
//     if (!ev.running) { sleep 10 ms; continue; }  // IDLE: not yet (or no longer) running
//     xr->Frame(update, renderEye);                // wait, sync actions, update, begin, eyes, end
//   }
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/xr/math.h"

namespace sphxr::xr {

enum class Hand { kLeft = 0, kRight = 1 };
constexpr int kHandCount = 2;

/// The session states of the OpenXR specification (section "Session Lifecycle").
enum class SessionState { kUnknown, kIdle, kReady, kSynchronized, kVisible, kFocused, kStopping, kLossPending, kExiting };
const char* SessionStateName(SessionState state);

/// What the application hands in to make its GL context the session's. One member per platform
/// binding of XR_KHR_opengl_enable; Linux uses Xlib/GLX, Windows would fill `win32` (see docs/dev/xr.md).
struct GraphicsBinding {
  /// Loads GL entry points (glfwGetProcAddress, eglGetProcAddress, ...): xr needs a few GL 3.0
  /// framebuffer functions and does not bring its own loader.
  void* (*getProcAddress)(const char* name) = nullptr;
  struct XlibGlx {
    void* display = nullptr;        // Display*
    unsigned long drawable = 0;     // GLXDrawable
    void* context = nullptr;        // GLXContext
  } xlib;
  struct Win32Wgl {
    void* hDC = nullptr;
    void* hGLRC = nullptr;
  } win32;
};
/// Fills `xlib` from the GLX context current on this thread (display may be glfwGetX11Display()).
Status CurrentXlibGlxBinding(void* display, GraphicsBinding* binding);

struct SessionOptions {
  std::string applicationName = "sphxr";
  float nearZ = 0.05f, farZ = 100.0f;
  bool wantDepth = true;
  /// Haptic pulse length of ApplyHaptics; the application re-sends each frame while it wants more.
  float hapticPulseSeconds = 0.05f;
};

/// One hand's input at the predicted display time of the frame.
struct HandState {
  bool poseValid = false;  // the grip pose is known (possibly not tracked, e.g. inferred)
  bool tracked = false;    // position and orientation tracked
  Pose grip;               // in the play space
  bool velocityValid = false;
  Vec3 linearVelocity, angularVelocity;  // m/s, rad/s in the play space
  float trigger = 0, squeeze = 0;        // 0..1
  bool active = false;                   // the runtime reports the actions bound and the session focused
};

struct FrameInfo {
  int64_t predictedDisplayTimeNs = 0;
  int64_t displayPeriodNs = 0;
  bool shouldRender = false;
  uint64_t frameIndex = 0;
  std::array<HandState, kHandCount> hands;
  bool recentred = false;       // the recentre button was pressed: the play space moved this frame
  bool resetRequested = false;  // the reset button was pressed (the application resets its scene)
  bool saveRequested = false;   // the save button was pressed (the application saves its state)
};

/// One eye to draw: the framebuffer is bound and the viewport set when the callback runs.
struct EyeView {
  int eye = 0;  // 0 left, 1 right
  Pose pose;    // eye in the play space
  Fov fov;
  Mat4 view, projection;  // OpenGL conventions, projection from SessionOptions near/far
  uint32_t framebuffer = 0, colorTexture = 0, depthTexture = 0;
  int x = 0, y = 0, width = 0, height = 0;
  bool srgb = false;  // the colour image is sRGB: enable GL_FRAMEBUFFER_SRGB when writing linear colour
};

struct EventResult {
  SessionState state = SessionState::kUnknown;
  bool running = false;  // between xrBeginSession and xrEndSession: call Frame()
  bool exit = false;     // stop the loop: the session is over (see `message`)
  bool lost = false;     // the session or instance was lost (the application may fall back)
  std::string message;   // why `exit`, one line
  std::vector<SessionState> transitions;  // every state change seen by this call, in order
};

/// Where the last Frame() spent its time (milliseconds, steady clock): for the frame-time tables.
struct FrameTimings {
  double waitMs = 0;    // in xrWaitFrame (mostly the runtime pacing the loop)
  double syncMs = 0;    // xrSyncActions, action states, hand locations
  double updateMs = 0;  // the application's update callback
  double renderMs = 0;  // xrBeginFrame, xrLocateViews, swapchain images and the eye callbacks
  double endMs = 0;     // xrEndFrame
};

/// Asks the loader whether an OpenXR runtime with XR_KHR_opengl_enable answers, without creating
/// an instance (for choosing the default mode). The error is the same one line as Create's.
Status ProbeRuntime();

using UpdateFn = std::function<void(const FrameInfo&)>;
using RenderEyeFn = std::function<void(const FrameInfo&, const EyeView&)>;

class Session {
 public:
  /// Creates instance, session, spaces, actions and swapchains. A missing runtime gives an error
  /// whose message is one line the application can print before falling back to desktop mode.
  static Status Create(const SessionOptions& options, const GraphicsBinding& binding, std::unique_ptr<Session>* out);
  ~Session();  // GL objects are deleted: keep the context current
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  /// Drains the runtime's events and drives the state machine (READY: begin, STOPPING: end).
  EventResult PollEvents();
  /// One frame: xrWaitFrame; sync actions and locate the hands at the predicted display time;
  /// `update`; xrBeginFrame; when shouldRender, locate the views and call `renderEye` for each eye
  /// with its swapchain image bound; xrEndFrame, always once the frame has begun.
  Status Frame(const UpdateFn& update, const RenderEyeFn& renderEye);
  /// Vibrates one controller for SessionOptions::hapticPulseSeconds; amplitude is clamped to 0..1,
  /// and 0 stops the vibration.
  Status ApplyHaptics(Hand hand, float amplitude);
  /// Moves the play space so that the head is at its origin (on the floor), facing -z.
  Status Recentre();
  /// Asks the runtime to end the session (the loop then sees STOPPING, EXITING and `exit`).
  Status RequestExit();

  SessionState state() const;
  const FrameTimings& lastFrameTimings() const;
  std::string runtimeName() const;
  std::string interactionProfile(Hand hand) const;
  int eyeWidth() const;
  int eyeHeight() const;
  int64_t colorFormat() const;  // the GL internal format chosen
  int64_t depthFormat() const;  // 0 when the runtime offered no depth format
  /// True when each view's depth goes to the compositor (XR_KHR_composition_layer_depth).
  bool submitsDepth() const;

  struct Impl;

 private:
  explicit Session(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> m_impl;
};

}  // namespace sphxr::xr
