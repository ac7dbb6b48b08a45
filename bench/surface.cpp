// sphxr_bench_surface: the cost of the water surface (histogram-pyramid marching cubes) on
// scenes/dam_break_1m.json mid-collapse, CPU backend.
//
// Runs the scene to --time (default 0.5 s: the column has landed and is collapsing), then, side by side
// in one process: the median time of a simulation step (20 steps), and for each surface cell size
// (spacing and spacing/2) the median over --repeat extractions of the three phases (field: re-grid,
// bounding box, near flags, field gather; pyramid: base level and reductions; traversal: one thread per
// vertex), and the median of 3 runs of the plain serial marching cubes of tests/sim/reference_mc.h on
// the same field (positions and normals, as the traversal writes). Memory: the pyramid against its base
// level. Prints a markdown table; --csv appends one row per cell size. Reports, never asserts.
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
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
    "usage: sphxr_bench_surface [--threads N] [--time S] [--repeat N] [--csv FILE] [--scene FILE]\n"
    "  --threads N  CPU backend threads (default 2)\n"
    "  --time S     simulated time before measuring (default 0.5 s, mid-collapse)\n"
    "  --repeat N   extractions per cell size (default 15)\n"
    "  --csv FILE   append one row per cell size\n"
    "  --scene FILE (default " SPHXR_SCENES_DIR "/dam_break_1m.json)\n";

int Run(int argc, char** argv) {
  int threads = 2, repeat = 15;
  double time = 0.5;
  std::string csv, scenePath = SPHXR_SCENES_DIR "/dam_break_1m.json";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (a == "--threads" && hasValue) threads = std::atoi(argv[++i]);
    else if (a == "--time" && hasValue) time = std::atof(argv[++i]);
    else if (a == "--repeat" && hasValue) repeat = std::atoi(argv[++i]);
    else if (a == "--csv" && hasValue) csv = argv[++i];
    else if (a == "--scene" && hasValue) scenePath = argv[++i];
    else {
      std::fprintf(stderr, "%s", kUsage);
      return a == "--help" ? 0 : 2;
    }
  }
  if (threads < 1 || repeat < 1 || !(time >= 0.0)) {
    std::fprintf(stderr, "--threads and --repeat must be at least 1, --time not negative\n%s", kUsage);
    return 2;
  }
  app::SceneFile scene;
  if (Status s = app::LoadScene(scenePath, &scene); !s) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
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

  std::ofstream out;
  if (!csv.empty() &&
      !OpenCsv(csv,
               "timestamp,cpu,threads,load_before,load_after,scene,fluid,time_s,cell_size_m,cell_over_spacing,samples,"
               "cells,triangles,field_ms,pyramid_ms,traversal_ms,extraction_ms,step_ms,reference_mc_ms,"
               "pyramid_over_base,base_bytes,pyramid_bytes,field_bytes",
               true, &out)) {
    std::fprintf(stderr, "--csv %s: cannot open\n", csv.c_str());
    return 1;
  }
  struct Row {
    float cell;
    sim::SurfaceStats stats;
    double field, pyramid, traversal, reference;
  };
  std::vector<Row> rows;
  for (float factor : {1.0f, 0.5f}) {
    sim::SurfaceParams params;
    params.cellSize = factor * spacing;
    std::vector<double> field, pyramid, traversal;
    sim::SurfaceStats stats;
    for (int r = 0; r < repeat; ++r) {
      sim::SurfaceMeshView view;
      if (Status s = solver->ExtractSurface(params, &view, &stats); !s) {
        std::fprintf(stderr, "%s\n", s.message().c_str());
        return 1;
      }
      field.push_back(1e3 * stats.fieldSeconds);
      pyramid.push_back(1e3 * stats.pyramidSeconds);
      traversal.push_back(1e3 * stats.traversalSeconds);
    }
    sim::SurfaceGrid grid;
    std::vector<float> values;
    solver->BackendForTests()->Surface()->DownloadField(&grid, &values);
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
    rows.push_back({params.cellSize, stats, Median(field), Median(pyramid), Median(traversal), Median(reference)});
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
  return 0;
}

}  // namespace
}  // namespace sphxr::bench

int main(int argc, char** argv) { return sphxr::bench::Run(argc, argv); }
