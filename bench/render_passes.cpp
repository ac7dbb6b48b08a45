// Time per render pass and per eye (each pass finished and timed: RendererConfig::finishEachPass, exact
// on llvmpipe, where a GL_TIME_ELAPSED query can hold another pass's binned work), on `stir`
// after 0.5 simulated s (still water on the table) and `dam_break` after 0.3 s (the run-up jet with its
// spray, foam and bubbles), one eye looking at the tank from a standing position at arm's reach, at
// 512x512 and 1024x1024, at each render quality.
// The medians of `--frames` frames, each drawn and finished before the next. Reports; never asserts.
// Usage: sphxr_bench_render_passes [--frames N] [--csv FILE]   (default bench/results/render_passes.csv)
#include <epoxy/gl.h>

#include <cstdio>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <algorithm>
#include <map>
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

int main(int argc, char** argv) {
  using namespace sphxr;
  int frames = 20;
  std::string csvPath = "bench/results/render_passes.csv";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc) {
      if (!bench::IntegerOption("sphxr_bench_render_passes", a, argv[++i], 3, 100000, &frames)) return 2;
    } else if (a == "--csv" && i + 1 < argc) {
      csvPath = argv[++i];
    } else {
      std::fprintf(stderr, "usage: sphxr_bench_render_passes [--frames N] [--csv FILE]\n");
      return 2;
    }
  }
  const std::string header = "machine,gl,load_avg_start,scene,eye_px,quality,fluid,triangles,diffuse,pass,gpu_ms_median";
  if (std::string why = bench::CsvRefusal(csvPath, header); !why.empty()) return std::fprintf(stderr, "%s\n", why.c_str()), 2;

  const double load = bench::LoadAverage();  // before this bench's own work raises it
  std::unique_ptr<render::HeadlessContext> context;
  if (Status s = render::HeadlessContext::Create(false, &context); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  // Two states: stir at 0.5 s (still water: the table, the glass, the paddle-less tank) and the dam
  // break at 0.3 s (its run-up jet with spray, foam and bubbles).
  struct Case {
    const char* name;
    const char* file;
    double time;
  };
  const Case cases[] = {{"stir", SPHXR_SCENES_DIR "/stir.json", 0.5}, {"dam_break", SPHXR_SCENES_DIR "/dam_break.json", 0.3}};
  struct State {
    std::string name;
    app::SceneFile scene;
    app::SimSnapshot snap;
    int fluid = 0;
  };
  std::vector<State> states;
  for (const Case& c : cases) {
    State st;
    st.name = c.name;
    if (Status s = app::LoadScene(c.file, &st.scene); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
    sim::SolverConfig sc;
    sc.device = sim::Device::kCpu;
    std::unique_ptr<sim::Solver> solver;
    if (Status s = sim::Solver::Create(st.scene.setup, sc, &solver); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
    while (solver->Time() < c.time) {
      if (Status s = solver->Step(); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
    }
    app::SurfaceRequest surface;
    surface.params = st.scene.surface.value_or(sim::SurfaceParams{});
    if (Status s = app::CaptureSnapshot(*solver, nullptr, surface, &st.snap); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
    st.snap.setup = st.scene.setup;
    st.fluid = solver->FluidCount();
    states.push_back(std::move(st));
  }
  std::ofstream csv;
  if (std::string why = bench::OpenCsv(csvPath, header, /*append=*/false, &csv); !why.empty()) {
    return std::fprintf(stderr, "%s\n", why.c_str()), 2;
  }
  const std::string machine = bench::CpuModel();
  std::printf("machine: %s, load %.2f; GL %s\n\n", machine.c_str(), load, render::GlDescription());
  for (const State& st : states) {
    const render::FrameScene frame = app::MakeFrameScene(st.snap, render::RenderMode::kWater);
    // The simulated headset's default head (xr/sim_runtime: 0.55 m above the tank's centre and 0.5 m in
    // front of it, looking at it), in the scene's frame.
    const sim::Aabb& tank = st.scene.setup.tank;
    const glm::vec3 centre(0.5f * (tank.min.x + tank.max.x), 0.5f * (tank.min.y + tank.max.y), 0.5f * (tank.min.z + tank.max.z));
    const float reach = std::max(0.5f, 1.2f * (tank.max.x - tank.min.x));
    const glm::mat4 viewMatrix = glm::lookAt(centre + glm::vec3(0.0f, 1.1f * reach, reach), centre, glm::vec3(0, 1, 0));
    std::printf("%s: %d particles, %lld triangles, %d diffuse\n", st.name.c_str(), st.fluid,
                static_cast<long long>(st.snap.surface.TriangleCount()), st.snap.diffuse.count);
    for (const int size : {512, 1024}) {
      std::unique_ptr<render::OffscreenTarget> target;
      if (Status s = render::OffscreenTarget::Create(size, size, &target); !s) return 1;
      for (const render::RenderQuality quality : {render::RenderQuality::kHigh, render::RenderQuality::kMedium, render::RenderQuality::kLow}) {
        render::RendererConfig config;
        config.debug = false;
        config.quality = quality;
        config.finishEachPass = true;  // each pass finished and timed on the clock: exact on llvmpipe
        std::unique_ptr<render::Renderer> renderer;
        if (Status s = render::Renderer::Create(config, &renderer); !s) return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
        render::View view;
        view.view = viewMatrix;
        view.projection = glm::perspective(1.6f, 1.0f, 0.05f, 100.0f);  // the simulated eye's 92 degrees
        view.framebuffer = target->Framebuffer();
        view.width = view.height = size;
        std::vector<std::string> order;
        std::map<std::string, std::vector<double>> ms;
        for (int f = 0; f < frames + 2; ++f) {
          renderer->Draw(frame, std::span(&view, 1));
          glFinish();
          if (f < 2) continue;  // the first frames' queries are not in yet
          for (const render::PassTime& p : renderer->LastStats().passes) {
            if (!ms.count(p.name)) order.push_back(p.name);
            ms[p.name].push_back(p.gpuMs);
          }
        }
        double total = 0.0;
        std::printf("  %dx%d %-6s", size, size, render::RenderQualityName(quality));
        for (const std::string& name : order) {
          const double median = bench::Median(ms[name]);
          total += median;
          std::printf("  %s %.2f", name.c_str(), median);
          csv << bench::CsvField(machine) << ',' << bench::CsvField(render::GlDescription()) << ',' << load << ',' << st.name
              << ',' << size << ',' << render::RenderQualityName(quality) << ',' << st.fluid << ','
              << st.snap.surface.TriangleCount() << ',' << st.snap.diffuse.count << ',' << bench::CsvField(name) << ','
              << median << '\n';
        }
        std::printf("  | all %.2f ms\n", total);
      }
    }
  }
  std::printf("\nwrote %s\n", csvPath.c_str());
  return 0;
}
