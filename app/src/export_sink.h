#pragma once
// `--export-every` and `--export-surface-every` (or their intervals), a sink of the Simulation
// (simulation.h): particle and surface files into --out DIR.
#include <cstdint>
#include <optional>

#include "sphxr/app/headless.h"
#include "sphxr/app/options.h"
#include "sphxr/app/simulation.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

/// --export-every K and --export-surface-every K: particles (PLY, VTK) and the surface mesh (PLY, OBJ)
/// into --out DIR, at the start when its step is one of theirs, every K steps, and once more at the
/// step a signal stopped the run. --export-interval S and --export-surface-interval S instead: at the
/// first step at or after each multiple of S simulated seconds (the start when it is one). Every file
/// names its step and time (export.h ExportStamp).
class ExportSink : public SimulationSink {
 public:
  ExportSink(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary)
      : m_options(options), m_surface(surface), m_summary(summary) {}
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  Status Finish(Simulation& simulation, bool interrupted) override;
  /// Mean extraction time in s, over the surfaces exported.
  double SurfaceSeconds() const { return m_surfaceSeconds; }

 private:
  Status Particles(Simulation& simulation, int64_t step);
  Status Surface(Simulation& simulation, int64_t step);
  /// The exports due now, by step count or by simulated time.
  Status Due(Simulation& simulation);
  /// By time: the multiple `*next` of `interval` is reached at `time`; moves `*next` past it.
  static bool Reached(double interval, double time, int64_t* next);

  const Options& m_options;
  std::optional<sim::SurfaceParams> m_surface;
  RunSummary* m_summary;
  sim::HostFluid m_host;
  sim::HostDiffuse m_diffuse;
  sim::SurfaceMesh m_mesh;
  double m_surfaceSeconds = 0.0;
  int64_t m_nextParticles = 0, m_nextSurface = 0;      // by time: the next multiple of the interval
  int64_t m_particlesStep = -1, m_surfaceStep = -1;    // the step of the last file written
};

}  // namespace sphxr::app
