#pragma once
// The GLFW window with an OpenGL 4.5 core context that the desktop mode (desktop.cpp) and the headset's
// mirror (xr_mode.cpp) draw into, with Dear ImGui on it: one place for the context hints, the one-line
// errors and the teardown order.
#include <string>

#include "sphxr/common/status.h"

struct GLFWwindow;

namespace sphxr::app {

struct GlWindowRequest {
  int width = 1280, height = 720;
  std::string title = "sphxr";
  std::string what = "a window";  // for the error lines: "cannot open <what>: ..."
  bool debug = false;             // a GL debug context (the renderer installs its callback)
  bool vsync = false;
};

/// glfwInit, the GL 4.5 core hints, the window; its context is current and the swap interval set.
/// On failure GLFW is terminated again and the status says why in one line.
Status OpenGlWindow(const GlWindowRequest& request, GLFWwindow** window);
/// Dear ImGui on the window, with the GLFW and OpenGL 3 backends; no imgui.ini is written. Install the
/// application's own GLFW callbacks first: ImGui's backend chains to them.
void InitImGui(GLFWwindow* window);
/// Shuts ImGui down (when InitImGui ran), destroys the window and terminates GLFW. Release GL objects
/// (renderer, interop buffers) before, with the window's context current.
void CloseGlWindow(GLFWwindow* window, bool imguiReady);

}  // namespace sphxr::app
