// sphxr_bench_surface: the cost of the water surface (histogram-pyramid marching cubes) on
// scenes/dam_break_1m.json mid-collapse, CPU backend.
//
// Runs the scene to --time (default 0.5 s: the column has landed and is collapsing), then, side by side
// in one process: the median time of a simulation step (20 steps), and for each surface cell size
// (spacing and spacing/2) the median over --repeat extractions of the three phases (field: re-grid,
// bounding box, field gather; pyramid: base level and reductions; traversal: a descent per run of
// --run vertices, 256 by default), and the median of 3 runs of the plain serial marching cubes of
// tests/sim/reference_mc.h on the same field (positions and normals, as the traversal writes). Memory:
// the pyramid against its base level. Prints a markdown table; --csv appends one row per cell size.
// --compare-runs then traverses the last pyramid of each cell size again with each run length in
// turn (rounds alternate, so a load that varies hits them alike) and checks that their meshes are
// bitwise the same. Reports, never asserts.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "backend.h"
#include "bench_util.h"
#include "reference_mc.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/surface.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::bench {
namespace {

const char* kUsage =
    "usage: sphxr_bench_surface [--threads N] [--time S] [--repeat N] [--run K] [--compare-runs K,K,...]\n"
    "                           [--csv FILE] [--scene FILE] [--device D]\n"
    "  --threads N  CPU backend threads (default 2)\n"
    "  --device D   cpu (default), cuda or cpu-reference (scripts/gpu_check.sh times cuda)\n"
    "  --time S     simulated time before measuring (default 0.5 s, mid-collapse)\n"
    "  --repeat N   extractions per cell size (default 15)\n"
    "  --run K      traversal vertices per work item (default 0: the backend's, 256)\n"
    "  --compare-runs K,K,...  then the traversal alone at each run length, 10 x --repeat\n"
    "               rounds alternating (K = 1: a descent per vertex)\n"
    "  --csv FILE   append one row per cell size\n"
    "  --scene FILE (default " SPHXR_SCENES_DIR "/dam_break_1m.json)\n";

double ProcessCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

constexpr int kCompareRounds = 10;  // --compare-runs rounds per --repeat: a traversal alone is short

int Run(int argc, char** argv) {
  int threads = 2, repeat = 15, run = 0;
  std::vector<int> compareRuns;
  double time = 0.5;
  std::string csv, scenePath = SPHXR_SCENES_DIR "/dam_break_1m.json";
  sim::Device device = sim::Device::kCpu;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    // A bad number gets one line naming it (the usage would not say which), checked before the scene loads.
    bool ok = true;
    auto integer = [&](long lo, long hi, int* out) { return IntegerOption("sphxr_bench_surface", a, argv[++i], lo, hi, out); };
    if (a == "--threads" && hasValue) ok = integer(1, 1024, &threads);
    else if (a == "--repeat" && hasValue) ok = integer(1, 1000000, &repeat);
    else if (a == "--run" && hasValue) ok = integer(0, 1000000, &run);  // 0: the backend's run length
    else if (a == "--time" && hasValue) {
      const char* v = argv[++i];
      if (!ParseNumber(v, &time) || time < 0.0) {
        std::fprintf(stderr, "sphxr_bench_surface: --time %s: must be a finite number, 0 or more (s)\n", v);
        ok = false;
      }
    } else if (a == "--compare-runs" && hasValue) {
      const char* v = argv[++i];
      for (std::stringstream list(v); ok && list.good();) {
        std::string k;
        std::getline(list, k, ',');
        long n = 0;
        ok = ParseInteger(k.c_str(), 1, 1000000, &n);  // an empty entry ("1,,2", "1,") fails too
        if (ok) compareRuns.push_back(static_cast<int>(n));
      }
      if (!ok) {
        std::fprintf(stderr, "sphxr_bench_surface: --compare-runs %s: must be integers from 1 to 1000000, comma-separated\n",
                     v);
      }
    } else if (a == "--device" && hasValue) {
      const char* v = argv[++i];
      if (!sim::ParseDevice(v, &device) || device == sim::Device::kAuto) {
        std::fprintf(stderr, "sphxr_bench_surface: --device %s: must be cpu, cuda or cpu-reference\n", v);
        ok = false;
      }
    } else if (a == "--csv" && hasValue) csv = argv[++i];
    else if (a == "--scene" && hasValue) scenePath = argv[++i];
    else {
      std::fprintf(stderr, "%s", kUsage);
      return a == "--help" ? 0 : 2;
    }
    if (!ok) return 2;
  }
  app::SceneFile scene;
  if (Status s = app::LoadScene(scenePath, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  sim::SolverConfig config;
  config.device = device;
  config.threads = threads;
  std::unique_ptr<sim::Solver> solver;
  if (Status s = sim::Solver::Create(scene.setup, config, &solver); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  const double loadBefore = LoadAverage();
  std::fprintf(stderr, "running %s to t = %.2f s (%d fluid particles, %d threads)...\n", scene.name.c_str(), time,
               solver->FluidCount(), threads);
  while (solver->Time() < time - 1e-9) {
    if (Status s = solver->Step(); !s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return 1;
    }
  }
  // A step of this scene at this moment, measured here so that the ratio comes from one run.
  std::vector<double> stepMs;
  for (int k = 0; k < 20; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    if (Status s = solver->Step(); !s) return 1;
    stepMs.push_back(Ms(std::chrono::steady_clock::now() - t0));
  }
  const double step = Median(stepMs);
  const float spacing = scene.setup.params.spacing;
  sim::SurfaceExtractor* surface = solver->BackendForTests()->Surface();
  surface->SetTraversalRun(run);

  std::ofstream out;
  if (const std::string why = csv.empty() ? std::string() : OpenCsv(csv,
               "timestamp,cpu,threads,load_before,load_after,scene,fluid,time_s,cell_size_m,cell_over_spacing,samples,"
               "cells,triangles,field_ms,pyramid_ms,traversal_ms,extraction_ms,step_ms,reference_mc_ms,"
               "pyramid_over_base,base_bytes,pyramid_bytes,field_bytes",
               true, &out);
      !why.empty()) {
    std::fprintf(stderr, "%s\n", why.c_str());
    return 1;
  }
  struct Row {
    float cell;
    sim::SurfaceStats stats;
    double field, pyramid, traversal, reference;
    std::vector<double> runTraversal, runTraversalMin, runTraversalCpu;  // per --compare-runs entry
    bool runsAgree = true;
    sim::LaunchCounts extract, buildWrite;  // one steady ExtractSurface; one BuildSurface + WriteSurface
  };
  std::vector<Row> rows;
  for (float factor : {1.0f, 0.5f}) {
    sim::SurfaceParams params;
    params.cellSize = factor * spacing;
    std::vector<double> field, pyramid, traversal;
    sim::SurfaceStats stats;
    sim::LaunchCounts extractCounts;
    for (int r = 0; r < repeat; ++r) {
      sim::SurfaceMeshView view;
      const sim::LaunchCounts before = solver->Counts();
      if (Status s = solver->ExtractSurface(params, &view, &stats); !s) {
        std::fprintf(stderr, "%s\n", s.message().c_str());
        return 1;
      }
      extractCounts = solver->Counts() - before;
      field.push_back(1e3 * stats.fieldSeconds);
      pyramid.push_back(1e3 * stats.pyramidSeconds);
      traversal.push_back(1e3 * stats.traversalSeconds);
    }
    sim::SurfaceGrid grid;
    std::vector<float> values;
    surface->DownloadField(&grid, &values);
    std::vector<double> reference;
    int64_t referenceVertices = 0;
    for (int r = 0; r < 3; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const test::ReferenceMesh mesh = test::ReferenceMarchingCubes(grid, values, params.isoLevel, /*normals=*/true);
      reference.push_back(Ms(std::chrono::steady_clock::now() - t0));
      referenceVertices = mesh.VertexCount();
    }
    if (referenceVertices != stats.vertices) {
      std::fprintf(stderr, "warning: the reference has %lld vertices, HPMC %lld\n",
                   static_cast<long long>(referenceVertices), static_cast<long long>(stats.vertices));
    }
    Row row{params.cellSize, stats, Median(field), Median(pyramid), Median(traversal), Median(reference), {}, {}, {}, true,
            extractCounts, {}};
    {  // the renderer's two phases into a buffer of its own (host memory here), as the GPU path runs them
      std::vector<float> positions(static_cast<size_t>(3 * stats.capacity)), normals(positions.size());
      uint32_t draw[4] = {};
      sim::SurfaceStats phases;
      const sim::LaunchCounts before = solver->Counts();
      if (Status s = solver->BuildSurface(params, &phases); !s) return 1;
      if (Status s = solver->WriteSurface({positions.data(), normals.data(), stats.capacity, draw}, &phases); !s) return 1;
      row.buildWrite = solver->Counts() - before;
    }
    if (!compareRuns.empty()) {
      // The last pyramid again, each run length in turn per round; the meshes against the first one's.
      std::vector<std::vector<double>> ms(compareRuns.size()), cpuMs(compareRuns.size());
      sim::SurfaceMesh first, other;
      for (int r = 0; r < kCompareRounds * repeat; ++r) {
        for (size_t i = 0; i < compareRuns.size(); ++i) {
          surface->SetTraversalRun(compareRuns[i]);
          sim::SurfaceMeshView view;
          sim::SurfaceStats runStats;
          const double cpu0 = ProcessCpuMs();
          if (Status s = surface->WriteOwned(&view, &runStats); !s) {
            std::fprintf(stderr, "%s\n", s.message().c_str());
            return 1;
          }
          ms[i].push_back(1e3 * runStats.traversalSeconds);
          cpuMs[i].push_back(ProcessCpuMs() - cpu0);
          if (r > 0) continue;
          surface->DownloadMesh(i == 0 ? &first : &other);
          if (i > 0) {
            row.runsAgree = row.runsAgree && other.positions.size() == first.positions.size() &&
                            std::memcmp(other.positions.data(), first.positions.data(), 4 * first.positions.size()) == 0 &&
                            std::memcmp(other.normals.data(), first.normals.data(), 4 * first.normals.size()) == 0;
          }
        }
      }
      surface->SetTraversalRun(run);
      for (size_t i = 0; i < ms.size(); ++i) {
        row.runTraversal.push_back(Median(ms[i]));
        row.runTraversalMin.push_back(*std::min_element(ms[i].begin(), ms[i].end()));
        row.runTraversalCpu.push_back(Median(cpuMs[i]));
      }
    }
    rows.push_back(row);
  }
  const double loadAfter = LoadAverage();

  std::printf("Machine: %s, nproc %d, %d threads, 1-minute load %.2f before, %.2f after\n", CpuModel().c_str(),
              CpuCount(), threads, loadBefore, loadAfter);
  std::printf("Scene %s at t = %.3f s, %d fluid particles; a simulation step here: %.2f ms (median of 20)\n\n",
              scene.name.c_str(), solver->Time(), solver->FluidCount(), step);
  std::printf("| cell size | lattice | triangles | field ms | pyramid ms | traversal ms | extraction ms | / step | "
              "reference MC ms | (pyramid + traversal) speed-up | pyramid / base memory |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows) {
    const double total = r.field + r.pyramid + r.traversal;
    const sim::SurfaceGrid& g = r.stats.grid;
    std::printf("| %.4g m (%.2g dx) | %d x %d x %d | %lld | %.2f | %.2f | %.2f | **%.2f** | %.2f | %.2f | **%.1fx** | "
                "%.3f |\n",
                r.cell, r.cell / spacing, g.nx, g.ny, g.nz, static_cast<long long>(r.stats.triangles), r.field,
                r.pyramid, r.traversal, total, total / step, r.reference, r.reference / (r.pyramid + r.traversal),
                static_cast<double>(r.stats.pyramidBytes) / static_cast<double>(r.stats.baseBytes));
    if (out) {
      out << UtcTimestamp() << ',' << CsvField(CpuModel()) << ',' << threads << ',' << loadBefore << ',' << loadAfter
          << ',' << scene.name << ',' << solver->FluidCount() << ',' << solver->Time() << ',' << r.cell << ','
          << r.cell / spacing << ',' << g.Samples() << ',' << g.Cells() << ',' << r.stats.triangles << ',' << r.field
          << ',' << r.pyramid << ',' << r.traversal << ',' << total << ',' << step << ',' << r.reference << ','
          << static_cast<double>(r.stats.pyramidBytes) / static_cast<double>(r.stats.baseBytes) << ','
          << r.stats.baseBytes << ',' << r.stats.pyramidBytes << ',' << r.stats.fieldBytes << '\n';
    }
  }
  std::printf("\nCounts per surface (the launch layer's: kernels, host waits, device allocations, copies back):\n\n"
              "| cell size | ExtractSurface (host copy's path) | BuildSurface + WriteSurface (in place) |\n|---|---|---|\n");
  for (const Row& r : rows) {
    auto text = [](const sim::LaunchCounts& c) {
      return Format("%lld / %lld / %lld / %lld", static_cast<long long>(c.launches), static_cast<long long>(c.syncs),
                    static_cast<long long>(c.allocations), static_cast<long long>(c.downloads));
    };
    std::printf("| %.4g m | %s | %s |\n", r.cell, text(r.extract).c_str(), text(r.buildWrite).c_str());
  }
  if (!compareRuns.empty()) {
    std::printf("\nThe traversal alone by run length (vertices per work item), %d alternating rounds (the minimum: the "
                "time least disturbed by other processes; CPU ms: the process's CPU time, all threads, spinning included\n"
                "unless OMP_WAIT_POLICY=passive):\n\n",
                kCompareRounds * repeat);
    std::printf("| cell size | run | traversal ms median | min | CPU ms | (pyramid + traversal) speed-up | mesh |\n"
                "|---|---:|---:|---:|---:|---:|---|\n");
    for (const Row& r : rows) {
      for (size_t i = 0; i < compareRuns.size(); ++i) {
        std::printf("| %.4g m | %d | %.2f | %.2f | %.2f | %.2fx | %s |\n", r.cell, compareRuns[i],
                    r.runTraversal[i], r.runTraversalMin[i], r.runTraversalCpu[i],
                    r.reference / (r.pyramid + r.runTraversal[i]),
                    i == 0 ? "" : (r.runsAgree ? "bitwise as the first" : "**DIFFERS**"));
      }
    }
  }
  return 0;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) { return sphxr::bench::Run(argc, argv); }
