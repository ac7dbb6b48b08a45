#include "gl_window.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "sphxr/common/log.h"

namespace sphxr::app {
namespace {

std::string g_glfwError;  // the last GLFW error, for one-line messages
void GlfwError(int code, const char* text) { g_glfwError = Format("%s (GLFW 0x%x)", text, code); }

}  // namespace

Status OpenGlWindow(const GlWindowRequest& request, GLFWwindow** window) {
  *window = nullptr;
  glfwSetErrorCallback(GlfwError);
  g_glfwError.clear();
  if (!glfwInit()) return Status::Error("cannot open " + request.what + ": " + g_glfwError);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, request.debug ? GLFW_TRUE : GLFW_FALSE);
  *window = glfwCreateWindow(request.width, request.height, request.title.c_str(), nullptr, nullptr);
  if (!*window) {
    glfwTerminate();
    return Status::Error("cannot open " + request.what + " with an OpenGL 4.5 core context: " + g_glfwError +
                         " (the renderer needs GL 4.5)");
  }
  glfwMakeContextCurrent(*window);
  glfwSwapInterval(request.vsync ? 1 : 0);
  return Status::Ok();
}

void InitImGui(GLFWwindow* window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 450 core");
}

void CloseGlWindow(GLFWwindow* window, bool imguiReady) {
  if (imguiReady) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  if (window) glfwDestroyWindow(window);
  if (window || imguiReady) glfwTerminate();
}

}  // namespace sphxr::app
