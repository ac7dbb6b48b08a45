#include "export_sink.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "sphxr/app/export.h"

namespace sphxr::app {

Status ExportSink::Particles(Simulation& simulation, int64_t step) {
  simulation.Solver().Download(&m_host);
  char name[64];
  std::snprintf(name, sizeof(name), "particles_%06lld.%s", static_cast<long long>(step), m_options.exportFormat.c_str());
  const std::string path = (std::filesystem::path(m_options.outDir) / name).string();
  const ExportStamp stamp{step, simulation.Solver().Time()};
  Status s = m_options.exportFormat == "vtk" ? WriteVtk(path, m_host, stamp) : WritePly(path, m_host, stamp);
  if (s && simulation.Solver().Scene().params.diffuse > 0.0f) {  // spray, foam and bubbles beside (always PLY)
    simulation.Solver().DownloadDiffuse(&m_diffuse);
    std::snprintf(name, sizeof(name), "diffuse_%06lld.ply", static_cast<long long>(step));
    s = WriteDiffusePly((std::filesystem::path(m_options.outDir) / name).string(), m_diffuse, stamp);
  }
  if (s) ++m_summary->exports;
  m_particlesStep = step;
  return s;
}

Status ExportSink::Surface(Simulation& simulation, int64_t step) {
  const auto t0 = std::chrono::steady_clock::now();
  sim::SurfaceStats stats;
  if (Status s = simulation.Solver().ExtractSurface(m_surface.value_or(sim::SurfaceParams{}), &m_mesh, &stats); !s) {
    return Status::Error(m_options.scenePath + ": " + s.message());
  }
  m_surfaceSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  char name[64];
  std::snprintf(name, sizeof(name), "surface_%06lld.%s", static_cast<long long>(step), m_options.surfaceFormat.c_str());
  const std::string path = (std::filesystem::path(m_options.outDir) / name).string();
  const ExportStamp stamp{step, simulation.Solver().Time()};
  Status s = m_options.surfaceFormat == "obj" ? WriteSurfaceObj(path, m_mesh, stamp) : WriteSurfacePly(path, m_mesh, stamp);
  if (s) {
    ++m_summary->surfaceExports;
    m_summary->surfaceTriangles = m_mesh.TriangleCount();
  }
  m_surfaceStep = step;
  return s;
}

bool ExportSink::Reached(double interval, double time, int64_t* next) {
  // A hair of slack: a time meant to be a multiple of the interval (a start at k S) counts as one.
  const double slack = 1e-9 * interval;
  if (time + slack < static_cast<double>(*next) * interval) return false;
  *next = static_cast<int64_t>(std::floor((time + slack) / interval)) + 1;
  return true;
}

Status ExportSink::Due(Simulation& simulation) {
  const int64_t step = simulation.WholeStep();
  const double time = simulation.Solver().Time();
  const bool particles = m_options.exportEvery > 0 ? step % m_options.exportEvery == 0
                                                   : m_options.exportInterval > 0.0 &&
                                                         Reached(m_options.exportInterval, time, &m_nextParticles);
  if (particles) {
    if (Status s = Particles(simulation, step); !s) return s;
  }
  const bool surface = m_options.exportSurfaceEvery > 0
                           ? step % m_options.exportSurfaceEvery == 0
                           : m_options.exportSurfaceInterval > 0.0 &&
                                 Reached(m_options.exportSurfaceInterval, time, &m_nextSurface);
  if (surface) {
    if (Status s = Surface(simulation, step); !s) return s;
  }
  return Status::Ok();
}

Status ExportSink::OnStart(Simulation& simulation) {
  // The start is exported when its step (or time) is one of the exports' (a fresh run's step 0): a
  // continued run then writes the files the whole run writes.
  const double time = simulation.Solver().Time();
  for (auto [interval, next] : {std::pair{m_options.exportInterval, &m_nextParticles},
                                std::pair{m_options.exportSurfaceInterval, &m_nextSurface}}) {
    if (interval > 0.0) *next = static_cast<int64_t>(std::ceil(time / interval - 1e-9));
  }
  return Due(simulation);
}

Status ExportSink::OnStep(Simulation& simulation, const sim::StepInfo&) { return Due(simulation); }

Status ExportSink::Finish(Simulation& simulation, bool interrupted) {
  if (!interrupted) return Status::Ok();
  // The state reached is not lost: one more export at this step unless it was just written.
  const int64_t step = simulation.WholeStep();
  if ((m_options.exportEvery > 0 || m_options.exportInterval > 0.0) && m_particlesStep != step) {
    if (Status s = Particles(simulation, step); !s) return s;
  }
  if ((m_options.exportSurfaceEvery > 0 || m_options.exportSurfaceInterval > 0.0) && m_surfaceStep != step) {
    if (Status s = Surface(simulation, step); !s) return s;
  }
  return Status::Ok();
}

}  // namespace sphxr::app
