// Solver's surface entry points (ExtractSurface, BuildSurface, WriteSurface): parameter checks and
// defaults, then the backend's HPMC stages (surface_impl.h). See docs/dev/surface.md.
#include <cmath>

#include "backend.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {
namespace {

// Field samples an extraction may allocate: about 9 bytes each (field, pyramid), so 1.2 GB.
constexpr int64_t kMaxSurfaceSamples = int64_t{1} << 27;

}  // namespace

Status Solver::BuildSurface(const SurfaceParams& params, SurfaceStats* stats) {
  SurfaceStats local;
  if (!stats) stats = &local;
  const float spacing = m_scene.params.spacing;
  if (!std::isfinite(params.cellSize) || params.cellSize < 0.0f || params.cellSize > 100.0f) {
    return Status::Error(Format("surface.cell_size = %g is invalid: must be from 0 (the particle spacing) to 100 m",
                                params.cellSize));
  }
  if (!std::isfinite(params.isoLevel) || params.isoLevel <= 0.0f || params.isoLevel >= 10.0f) {
    return Status::Error(Format("surface.iso_level = %g is invalid: must be above 0 and below 10 (the volume fraction "
                                "is about 1 inside the water; 0.5 is its surface)",
                                params.isoLevel));
  }
  if (!std::isfinite(params.margin) || params.margin > 100.0f) {
    return Status::Error(Format("surface.margin = %g is invalid: must be at most 100 m (negative: the kernel support)",
                                params.margin));
  }
  SurfaceJob job;
  job.cellSize = params.cellSize > 0.0f ? params.cellSize : spacing;
  job.isoLevel = params.isoLevel;
  job.margin = params.margin >= 0.0f ? params.margin : SupportRadius();
  job.boxMin = m_physics->domainMin;
  job.boxMax = m_physics->domainMax;
  job.volume = spacing * spacing * spacing;  // m / rho0
  job.kernel = CubicSpline::Make(SupportRadius());
  job.maxSamples = kMaxSurfaceSamples;
  const int64_t capacity = stats->capacity;
  *stats = SurfaceStats{};
  stats->capacity = capacity;
  return m_backend->Surface()->BuildFromParticles(job, stats);
}

Status Solver::WriteSurface(const SurfaceTarget& target, SurfaceStats* stats) {
  SurfaceStats local;
  return m_backend->Surface()->WriteTo(target, stats ? stats : &local);
}

SurfaceWriteReport Solver::LastSurfaceWrite() const { return m_backend->Surface()->LastWrite(); }

Status Solver::ExtractSurface(const SurfaceParams& params, SurfaceMeshView* view, SurfaceStats* stats) {
  SurfaceStats local;
  if (!stats) stats = &local;
  *view = SurfaceMeshView{};
  if (Status s = BuildSurface(params, stats); !s) return s;
  return m_backend->Surface()->WriteOwned(view, stats);
}

Status Solver::ExtractSurface(const SurfaceParams& params, SurfaceMesh* mesh, SurfaceStats* stats) {
  SurfaceMeshView view;
  *mesh = SurfaceMesh{};
  if (Status s = ExtractSurface(params, &view, stats); !s) return s;
  m_backend->Surface()->DownloadMesh(mesh);
  return Status::Ok();
}

}  // namespace sphxr::sim
