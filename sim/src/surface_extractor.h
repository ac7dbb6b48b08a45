#pragma once
// The interface between the Solver and a backend's HPMC stages (surface_impl.h, one template for both
// systems). Two phases, so that a renderer can size its own buffer between them: Build* samples the
// field and builds the pyramid (the apex is the vertex count); Write* walks the pyramid into memory.
#include <cstdint>
#include <vector>

#include "kernel.h"
#include "sphxr/sim/vec.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/surface.h"

namespace sphxr::sim {

/// Resolved parameters of an extraction from the particles (defaults applied by the Solver).
struct SurfaceJob {
  float cellSize;      // m
  float isoLevel;
  float margin;        // m
  Vec3 boxMin, boxMax; // m, the box the domain clamp keeps every fluid particle in: the lattice covers it
  float volume;        // m / rho0 of one fluid particle
  CubicSpline kernel;  // the solver's kernel
  int64_t maxSamples;  // refuse a lattice with more samples than this
};

class SurfaceExtractor {
 public:
  virtual ~SurfaceExtractor() = default;
  /// Field from the backend's particles (the clamp box + margin), then the pyramid. Reads nothing back.
  virtual Status BuildFromParticles(const SurfaceJob& job, SurfaceStats* stats) = 0;
  /// The pyramid over a given host field of grid.Samples() values (tests, benchmarks).
  virtual Status BuildFromField(const SurfaceGrid& grid, const std::vector<float>& field, float isoLevel,
                                SurfaceStats* stats) = 0;
  /// The report of the last write whose report has reached the host (no copy, no wait).
  virtual SurfaceWriteReport LastWrite() const = 0;
  /// Vertices per traversal work item (TraverseStage::run); 0 = this backend's default. The mesh is the
  /// same for every value (tests, benchmarks).
  virtual void SetTraversalRun(int vertices) = 0;
  /// Traversal into caller memory of this backend's memory space, clamped to its capacity (and
  /// reported); reads nothing back.
  virtual Status WriteTo(const SurfaceTarget& target, SurfaceStats* stats) = 0;
  /// Traversal into the extractor's own buffer, then one wait for its report: a mesh that did not fit
  /// grows the buffer (logged) and is written again, so the view holds the whole mesh.
  virtual Status WriteOwned(SurfaceMeshView* view, SurfaceStats* stats) = 0;
  /// Host copies of the last mesh written to the own buffer, and of the last field.
  virtual void DownloadMesh(SurfaceMesh* out) const = 0;
  virtual void DownloadField(SurfaceGrid* grid, std::vector<float>* field) const = 0;
};

}  // namespace sphxr::sim
