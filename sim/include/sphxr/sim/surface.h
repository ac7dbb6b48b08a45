#pragma once
// The water surface: histogram-pyramid marching cubes (HPMC, Dyken et al. 2008) over a smoothed fluid
// indicator of the particles. One source for both backends (sim/src/surface_stages.h); the mesh stays
// where the backend computes it (device memory on CUDA, host memory on the CPU backend).
//
// The field is the kernel-weighted fluid volume fraction
//     phi(x) = sum_j (m / rho0) W(|x - x_j|, H)
// with the solver's cubic spline and support H: about 1 inside the water, 0 beyond H of every particle,
// 0.5 half a spacing outside the outermost particle layer of a flat surface. The surface is phi = iso.
//
// The mesh is a triangle soup: vertex 3t, 3t+1, 3t+2 is triangle t, counter-clockwise seen from outside
// the water; positions and normals are float xyz (12 bytes each). No index buffer: see docs/dev/surface.md.
#include <cstdint>
#include <vector>

#include "sphxr/sim/vec.h"

namespace sphxr::sim {

/// What to extract. Defaults: a cell of one particle spacing, iso level 0.5, a margin of the kernel support.
struct SurfaceParams {
  float cellSize = 0.0f;  // m, edge of a marching-cubes cell; 0 = the particle spacing
  float isoLevel = 0.5f;  // phi at the surface (volume fraction; inside is phi > iso)
  float margin = -1.0f;   // m added around the fluid's bounding box; < 0 = the kernel support radius
};

/// The sample lattice of the field: nx * ny * nz samples at origin + (i, j, k) * cellSize, so
/// (nx-1)(ny-1)(nz-1) cells. Aligned to the neighbour grid's origin, so it does not swim between frames.
struct SurfaceGrid {
  Vec3 origin;
  float cellSize = 0.0f;
  int nx = 0, ny = 0, nz = 0;
  int64_t Samples() const { return static_cast<int64_t>(nx) * ny * nz; }
  int64_t Cells() const {
    return nx < 2 || ny < 2 || nz < 2 ? 0 : static_cast<int64_t>(nx - 1) * (ny - 1) * (nz - 1);
  }
};

/// What one extraction did, and what it cost.
struct SurfaceStats {
  SurfaceGrid grid;
  /// The mesh's size, 3 per triangle. Exact after ExtractSurface (which reads it back). BuildSurface and
  /// WriteSurface read nothing back: there they are the last write's SurfaceWriteReport (on the CUDA
  /// backend an earlier build's; 0 before the first write).
  int64_t vertices = 0;
  int64_t triangles = 0;
  bool clamped = false;       // that write's target was too small: it holds the first `capacity` vertices
  int pyramidLevels = 0;      // base level included
  int64_t baseBytes = 0;      // the pyramid's base level (vertex count per cell)
  int64_t pyramidBytes = 0;   // all levels, base included
  int64_t fieldBytes = 0;     // the sampled field (and the near-cell flags)
  int64_t capacity = 0;       // vertices the mesh buffer holds now
  bool grew = false;          // this call enlarged the mesh buffer (also logged)
  double fieldSeconds = 0.0;     // bounding box, near flags, field gather
  double pyramidSeconds = 0.0;   // base level and reductions up to the apex
  double traversalSeconds = 0.0; // one thread per vertex down the pyramid; positions and normals
};

/// The mesh where the backend keeps it: device pointers on the CUDA backend (map into GL with CUDA-GL
/// interop, or write straight into a mapped GL buffer with Solver::WriteSurface), host pointers on the
/// CPU backend (upload with glBufferSubData). Valid until the next extraction.
struct SurfaceMeshView {
  const float* positions = nullptr;  // xyz per vertex
  const float* normals = nullptr;    // xyz per vertex, unit length, pointing out of the water
  int64_t vertexCount = 0;
  bool onDevice = false;
};

/// Caller memory to write a mesh into (same memory space as SurfaceMeshView::onDevice says). A mesh
/// larger than `capacity` is clamped to its first `capacity` vertices (whole triangles when capacity is a
/// multiple of 3) and reported (SurfaceWriteReport); nothing is written past it.
struct SurfaceTarget {
  float* positions = nullptr;
  float* normals = nullptr;
  int64_t capacity = 0;  // vertices
  /// Optional: a glDrawArraysIndirect command {count, instanceCount, first, baseInstance} that the write
  /// fills on the device with {vertices written, 1, 0, 0}, so the mesh is drawn without its count
  /// reaching the host (a GL_DRAW_INDIRECT_BUFFER mapped through CUDA-GL interop).
  uint32_t* drawCommand = nullptr;
};

/// What a write of the mesh found, reported by the device into host-visible memory (mapped pinned
/// memory on the CUDA backend): read without a copy or a wait, so on the CUDA backend it is complete
/// once the device has finished that write (`write` numbers the writes; 0: none reported yet).
struct SurfaceWriteReport {
  int64_t vertices = 0;  // the mesh's size (the pyramid's apex)
  int64_t written = 0;   // min(vertices, capacity)
  int64_t capacity = 0;  // of the target written
  uint64_t write = 0;
  bool Clamped() const { return vertices > written; }
};

/// A host copy of the mesh.
struct SurfaceMesh {
  std::vector<float> positions;  // 3 floats per vertex
  std::vector<float> normals;
  int64_t VertexCount() const { return static_cast<int64_t>(positions.size() / 3); }
  int64_t TriangleCount() const { return VertexCount() / 3; }
};

}  // namespace sphxr::sim
