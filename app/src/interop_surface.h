#pragma once
// The GPU surface path's GL side (CUDA-GL interop, render/interop.h): the mesh the simulation thread's
// solver writes in place, so that a GPU backend's surface reaches the screen without a host copy.
#include <cstdint>
#include <memory>

#include "sim_worker.h"
#include "sphxr/render/interop.h"

namespace sphxr::app {

/// The GL thread's half of the GPU surface path (desktop window, headset): the InteropMesh the worker's
/// solver writes into. Destroy it with the GL context current.
class InteropSurface {
 public:
  /// For a snapshot whose surface stayed on the device (SimSnapshot::surfaceOnDevice): brings the mesh
  /// up to the snapshot's build (one write per build) and returns it for FrameScene::deviceSurface; else
  /// null (draw the snapshot's host mesh). A failure switches the worker to host copies (logged once).
  const render::InteropMesh* Update(SimWorker& worker, const SimSnapshot& snap);
  void Reset();

 private:
  std::unique_ptr<render::InteropMesh> m_mesh;
  uint64_t m_written = 0;  // the newest build in m_mesh
};

/// Vertices for the interop buffers of the next write, from their current capacity and the solver's
/// last write report (Solver::LastSurfaceWrite, a frame late on the CUDA device): unchanged while the
/// mesh fits; else max(1.25x the mesh, 1.5x the capacity, 3 x 4096), whole triangles, at most 2^26.
int64_t InteropCapacity(int64_t capacity, const sim::SurfaceWriteReport& last);

}  // namespace sphxr::app
