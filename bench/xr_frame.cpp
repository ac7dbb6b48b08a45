// sphxr_bench_xr_frame: where an XR frame's time goes in sphxr's xr layer, against the simulated
// headset at its default 90 Hz and 1024x1024 per eye, each eye only cleared (the renderer is not
// part of this measurement). Run side by side without and with the core validation layer.
// Needs an X display:  xvfb-run -a build/bench/sphxr_bench_xr_frame [--frames N]
// Reports; never asserts.
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>
extern "C" Display* glfwGetX11Display(void);
#undef Status
#undef Bool
#undef Success
#undef None

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "bench_util.h"
#include "sphxr/common/log.h"
#include "sphxr/xr/session.h"

namespace {

using namespace sphxr;

struct Stats {
  std::vector<double> v;
  double Pct(double p) const { return bench::Quantile(v, p); }
};

bool RunOnce(const char* label, bool validation, int frames) {
  if (validation) setenv("XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation", 1);
  else unsetenv("XR_ENABLE_API_LAYERS");
  xr::GraphicsBinding binding;
  binding.getProcAddress = [](const char* n) { return reinterpret_cast<void*>(glfwGetProcAddress(n)); };
  std::unique_ptr<xr::Session> session;
  Status s = xr::CurrentXlibGlxBinding(glfwGetX11Display(), &binding);
  if (s) s = xr::Session::Create({}, binding, &session);
  if (!s) {
    std::fprintf(stderr, "sphxr_bench_xr_frame: %s\n", s.message().c_str());
    return false;
  }
  Stats wait, sync, render, end, busy;
  int measured = 0, late = 0;
  int64_t lastDisplay = 0, period = 0;
  bool exitAsked = false;
  while (true) {
    xr::EventResult ev = session->PollEvents();
    if (ev.exit) break;
    if (!ev.running) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    if (measured >= frames && !exitAsked) {
      (void)session->RequestExit();
      exitAsked = true;
    }
    xr::FrameInfo info;
    Status f = session->Frame([&](const xr::FrameInfo& i) { info = i; },
                              [](const xr::FrameInfo&, const xr::EyeView&) {
                                glClearColor(0.1f, 0.2f, 0.3f, 1);
                                glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
                              });
    if (!f) {
      std::fprintf(stderr, "sphxr_bench_xr_frame: %s\n", f.message().c_str());
      return false;
    }
    if (!info.shouldRender || exitAsked) continue;  // warm-up frame and the stopping ones
    const xr::FrameTimings& t = session->lastFrameTimings();
    wait.v.push_back(t.waitMs);
    sync.v.push_back(t.syncMs);
    render.v.push_back(t.renderMs);
    end.v.push_back(t.endMs);
    busy.v.push_back(t.syncMs + t.updateMs + t.renderMs + t.endMs);
    period = info.displayPeriodNs;
    if (lastDisplay && info.predictedDisplayTimeNs - lastDisplay > period) ++late;
    lastDisplay = info.predictedDisplayTimeNs;
    ++measured;
  }
  std::printf("| %s | %d | %.3f / %.3f | %.3f / %.3f | %.3f / %.3f | %.3f / %.3f | %.3f / %.3f | %d (%.1f %%) |\n", label,
              measured, wait.Pct(0.5), wait.Pct(0.9), sync.Pct(0.5), sync.Pct(0.9), render.Pct(0.5), render.Pct(0.9),
              end.Pct(0.5), end.Pct(0.9), busy.Pct(0.5), busy.Pct(0.9), late,
              measured > 1 ? 100.0 * late / (measured - 1) : 0.0);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 300;
  // Checked before glfwInit: a bad option fails at once, also without a display.
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      if (!bench::IntegerOption("sphxr_bench_xr_frame", "--frames", argv[++i], 1, 1000000, &frames)) return 2;
    } else {
      std::fprintf(stderr, "usage: sphxr_bench_xr_frame [--frames N]\n");
      return std::strcmp(argv[i], "--help") == 0 ? 0 : 2;
    }
  }
  if (!std::getenv("XR_RUNTIME_JSON")) setenv("XR_RUNTIME_JSON", SPHXR_SIM_RUNTIME_JSON, 1);
  SetLogLevel(LogLevel::kWarn);
  if (!glfwInit()) {
    std::fprintf(stderr, "sphxr_bench_xr_frame: no X display (run under xvfb-run -a)\n");
    return 1;
  }
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  GLFWwindow* window = glfwCreateWindow(64, 64, "bench", nullptr, nullptr);
  if (!window) {
    std::fprintf(stderr, "sphxr_bench_xr_frame: no OpenGL 3.3 context\n");
    return 1;
  }
  glfwMakeContextCurrent(window);
  std::printf("machine: %s, %d CPUs, load %.2f; GL: %s\n", bench::CpuModel().c_str(), bench::CpuCount(),
              bench::LoadAverage(), reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
  std::printf("runtime: %s; %d frames per run, eyes cleared only\n\n", std::getenv("XR_RUNTIME_JSON"), frames);
  std::printf("| run | frames | wait ms (p50 / p90) | sync ms | begin + eyes ms | end ms | busy ms | late frames |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  bool ok = RunOnce("loader only", false, frames) && RunOnce("with core validation", true, frames);
  glfwDestroyWindow(window);
  glfwTerminate();
  return ok ? 0 : 1;
}
