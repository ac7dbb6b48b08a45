// Frame time by stage for the window's workload: one simulation step, the surface extraction (HPMC, as
// the window's simulation thread does it for a snapshot), and the render of one 1280x720 view (water
// from the surface mesh, water from the particles, particles), on dam_break and a 20k-particle tank. The render goes through the same
// renderer as the window, into an EGL offscreen target (Mesa llvmpipe here), timed to glFinish.
// Reports; never asserts. Usage: sphxr_bench_frame [--steps N] [--frames M] [--threads T]
#include <epoxy/gl.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench_util.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/snapshot.h"
#include "sphxr/render/gl_context.h"
#include "sphxr/render/renderer.h"
#include "sphxr/sim/solver.h"

namespace {

using sphxr::bench::Median;
using sphxr::bench::Ms;

const char* kUsage = "usage: sphxr_bench_frame [--steps N] [--frames M] [--threads T] [--device cpu|cuda|cpu-reference]\n";

}  // namespace

int main(int argc, char** argv) {
  using namespace sphxr;
  int steps = 30, frames = 10, threads = 0;  // threads 0: all cores
  sim::Device device = sim::Device::kCpu;
  // All options are checked here, before the GL context: a typo fails at once, also without a display.
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("%s", kUsage);
      return 0;
    }
    if (a == "--device" && i + 1 < argc) {
      if (!sim::ParseDevice(argv[++i], &device) || device == sim::Device::kAuto) {
        std::fprintf(stderr, "sphxr_bench_frame: --device %s: must be cpu, cuda or cpu-reference\n", argv[i]);
        return 2;
      }
      continue;
    }
    int* value = a == "--steps" ? &steps : a == "--frames" ? &frames : a == "--threads" ? &threads : nullptr;
    if (!value || i + 1 >= argc) {
      std::fprintf(stderr, "sphxr_bench_frame: %s '%s'\n%s", value ? "missing value after" : "unknown argument",
                   a.c_str(), kUsage);
      return 2;
    }
    const long lo = value == &threads ? 0 : 1, hi = value == &threads ? 1024 : 1000000;
    if (!bench::IntegerOption("sphxr_bench_frame", a, argv[++i], lo, hi, value)) return 2;
  }
  const int width = 1280, height = 720;
  std::unique_ptr<render::HeadlessContext> context;
  std::unique_ptr<render::OffscreenTarget> target;
  std::unique_ptr<render::Renderer> renderer;
  render::RendererConfig config;
  config.debug = false;
  if (Status s = render::HeadlessContext::Create(false, &context); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  if (Status s = render::OffscreenTarget::Create(width, height, &target); !s) return 1;
  if (Status s = render::Renderer::Create(config, &renderer); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  std::printf("machine: %s, %d cores, load %.2f; GL %s; %d steps, %d frames per row, %dx%d\n\n",
              bench::CpuModel().c_str(), bench::CpuCount(), bench::LoadAverage(), render::GlDescription(), steps,
              frames, width, height);
  std::printf("| scene | fluid particles | sim ms/step (median) | surface ms (median) | triangles | render ms, water from the mesh | render ms, water from particles | render ms, particles |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");

  struct Case {
    std::string name, file;
    float spacing;  // 0 = the scene's
  };
  const Case cases[] = {{"dam_break", SPHXR_SCENES_DIR "/dam_break.json", 0.0f},
                        {"tank_rest at 5.8 mm (20k)", SPHXR_SCENES_DIR "/tank_rest.json", 0.0058f}};
  for (const Case& c : cases) {
    app::SceneFile scene;
    if (Status s = app::LoadScene(c.file, &scene); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
    if (c.spacing > 0.0f) scene.setup.params.spacing = c.spacing;
    sim::SolverConfig sc;
    sc.device = device;
    sc.threads = threads;
    std::unique_ptr<sim::Solver> solver;
    if (Status s = sim::Solver::Create(scene.setup, sc, &solver); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
    (void)solver->Step();  // first touch
    std::vector<double> stepMs;
    for (int i = 0; i < steps; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      (void)solver->Step();
      stepMs.push_back(Ms(std::chrono::steady_clock::now() - t0));
    }
    app::SimSnapshot snap;
    app::SurfaceRequest surface;
    surface.params = scene.surface.value_or(sim::SurfaceParams{});
    std::vector<double> surfaceMs;
    for (int f = 0; f <= frames; ++f) {  // the first grows the mesh buffer
      if (Status s = app::CaptureSnapshot(*solver, nullptr, surface, &snap); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
      if (f > 0) surfaceMs.push_back(snap.surfaceMs);
    }
    snap.setup = scene.setup;
    const float aspect = static_cast<float>(width) / height;
    double renderMs[3];
    for (int mode = 0; mode < 3; ++mode) {
      const render::FrameScene frame =
          mode == 0 ? app::MakeFrameScene(snap, render::RenderMode::kWater)
                    : app::MakeFrameScene(scene.setup, snap.fluid, mode == 1 ? render::RenderMode::kWater : render::RenderMode::kParticles);
      const render::Camera camera = render::FrameBox(frame.tank, aspect);
      render::View view;
      view.view = camera.View();
      view.projection = camera.Projection(aspect);
      view.framebuffer = target->Framebuffer();
      view.width = width;
      view.height = height;
      renderer->Draw(frame, std::span(&view, 1));  // warm-up (shader variants, buffer growth)
      glFinish();
      std::vector<double> ms;
      for (int f = 0; f < frames; ++f) {
        const auto t0 = std::chrono::steady_clock::now();
        renderer->Draw(frame, std::span(&view, 1));
        glFinish();
        ms.push_back(Ms(std::chrono::steady_clock::now() - t0));
      }
      renderMs[mode] = Median(ms);
    }
    std::printf("| %s | %d | %.2f | %.2f | %lld | %.1f | %.1f | %.1f |\n", c.name.c_str(), solver->FluidCount(),
                Median(stepMs), Median(surfaceMs), static_cast<long long>(snap.surface.TriangleCount()), renderMs[0],
                renderMs[1], renderMs[2]);
  }
  return 0;
}
