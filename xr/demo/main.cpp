// sphxr_xr_demo: the XR frame loop on its own, for trying a headset (or the simulated one) before
// the full application: each eye is cleared to a dark blue, each controller drawn as a square at
// its projected grip position (brighter with the trigger), the trigger drives that hand's haptics,
// and the window mirrors the left eye. Also the reference loop for wiring `sphxr --xr`.
//
//   XR_RUNTIME_JSON=build/xr/sim_runtime/sphxr_sim_runtime.json build/xr/sphxr_xr_demo --frames 300
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>
extern "C" Display* glfwGetX11Display(void);  // glfw3native.h, without its Xrandr include
#undef Status
#undef Bool
#undef Success
#undef None

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "sphxr/common/log.h"
#include "sphxr/xr/session.h"

namespace {

using namespace sphxr;

void DrawEye(const xr::FrameInfo& frame, const xr::EyeView& eye) {
  glDisable(GL_SCISSOR_TEST);
  glClearColor(0.02f, 0.05f, 0.15f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_SCISSOR_TEST);
  for (int h = 0; h < xr::kHandCount; ++h) {
    const xr::HandState& hand = frame.hands[size_t(h)];
    if (!hand.poseValid) continue;
    xr::Mat4 clip = eye.projection * eye.view;
    const xr::Vec3 p = hand.grip.position;
    float c[4];
    for (int r = 0; r < 4; ++r) c[r] = clip(r, 0) * p.x + clip(r, 1) * p.y + clip(r, 2) * p.z + clip(r, 3);
    if (c[3] <= 0) continue;  // behind the eye
    int px = int((c[0] / c[3] * 0.5f + 0.5f) * float(eye.width));
    int py = int((c[1] / c[3] * 0.5f + 0.5f) * float(eye.height));
    int half = std::max(2, eye.width / 40);
    glScissor(px - half, py - half, 2 * half, 2 * half);
    float g = 0.4f + 0.6f * hand.trigger;
    glClearColor(h == 0 ? g : 0.1f, h == 0 ? 0.1f : g, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
  }
  glDisable(GL_SCISSOR_TEST);
}

// The frame loop until the session ends: the triggers buzz their controllers, the left eye is mirrored
// into the window. 1 when a frame failed.
int RunSession(xr::Session& session, GLFWwindow* window, long maxFrames) {
  long frames = 0;
  bool exitAsked = false;
  bool mirrored = false;
  float lastAmplitude[xr::kHandCount] = {0, 0};
  while (true) {
    glfwPollEvents();
    if ((glfwWindowShouldClose(window) || (maxFrames >= 0 && frames >= maxFrames)) && !exitAsked) {
      if (Status e = session.RequestExit(); !e) std::fprintf(stderr, "sphxr_xr_demo: %s\n", e.message().c_str());
      exitAsked = true;
    }
    xr::EventResult ev = session.PollEvents();
    if (ev.exit) {
      std::printf("sphxr_xr_demo: %s after %ld frames%s\n", ev.message.c_str(), frames,
                  ev.lost ? " (the application would fall back to desktop mode)" : "");
      break;
    }
    if (!ev.running) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    Status f = session.Frame(
        [&](const xr::FrameInfo& frame) {
          ++frames;
          for (int h = 0; h < xr::kHandCount; ++h) {
            float amplitude = frame.hands[size_t(h)].trigger;
            if (amplitude == 0 && lastAmplitude[h] == 0) continue;  // stop once, not every frame
            lastAmplitude[h] = amplitude;
            if (Status hs = session.ApplyHaptics(xr::Hand(h), amplitude); !hs)
              std::fprintf(stderr, "sphxr_xr_demo: %s\n", hs.message().c_str());
          }
        },
        [&](const xr::FrameInfo& frame, const xr::EyeView& eye) {
          DrawEye(frame, eye);
          if (eye.eye != 0) return;
          // Mirror now, while the image is ours: once released it belongs to the compositor.
          int w = 0, h = 0;
          glfwGetFramebufferSize(window, &w, &h);
          glBindFramebuffer(GL_READ_FRAMEBUFFER, eye.framebuffer);
          glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
          glDisable(GL_FRAMEBUFFER_SRGB);  // copy the encoded bytes as they are
          glBlitFramebuffer(0, 0, eye.width, eye.height, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_LINEAR);
          glBindFramebuffer(GL_FRAMEBUFFER, eye.framebuffer);  // xr restores its own binding after
          mirrored = true;
        });
    if (!f) {
      std::fprintf(stderr, "sphxr_xr_demo: %s\n", f.message().c_str());
      return 1;
    }
    if (mirrored) glfwSwapBuffers(window);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  long maxFrames = -1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      maxFrames = std::strtol(argv[++i], nullptr, 10);
    } else {
      std::fprintf(stderr, "usage: sphxr_xr_demo [--frames N]\n");
      return 2;
    }
  }
  if (!glfwInit()) {
    std::fprintf(stderr, "sphxr_xr_demo: no display (set DISPLAY, or run under xvfb-run)\n");
    return 1;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  GLFWwindow* window = glfwCreateWindow(640, 360, "sphxr xr demo (left eye)", nullptr, nullptr);
  if (!window) {
    std::fprintf(stderr, "sphxr_xr_demo: no OpenGL 3.3 context\n");
    glfwTerminate();
    return 1;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(0);  // the headset paces the loop, not the mirror window

  int code = 0;
  {
    xr::GraphicsBinding binding;
    binding.getProcAddress = [](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); };
    std::unique_ptr<xr::Session> session;
    Status s = xr::CurrentXlibGlxBinding(glfwGetX11Display(), &binding);
    if (s) s = xr::Session::Create({}, binding, &session);
    if (!s) {
      // The application prints this line and falls back to desktop mode; the demo has nothing else.
      std::fprintf(stderr, "sphxr_xr_demo: %s\n", s.message().c_str());
    } else {
      std::printf("sphxr_xr_demo: runtime '%s', %dx%d per eye\n", session->runtimeName().c_str(), session->eyeWidth(),
                  session->eyeHeight());
      code = RunSession(*session, window, maxFrames);
    }
  }
  glfwDestroyWindow(window);
  glfwTerminate();
  return code;
}
