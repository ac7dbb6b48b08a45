#pragma once
// A surface mesh that lives in OpenGL buffers and is written by CUDA in place (CUDA-GL interop), so a
// GPU backend's HPMC output reaches the screen without a host copy. The GL side is always built (the
// renderer draws these buffers like any mesh); Map/Unmap exist only in builds with the CUDA backend
// (SPHXR_HAVE_CUDA) and need a GPU: on a machine without one they are compiled, not run.
#include <cstdint>
#include <memory>

#include "sphxr/common/status.h"

namespace sphxr::render {

class InteropMesh {
 public:
  /// GL buffers for up to `maxVertices` vertices (xyz positions and normals, non-indexed triangles).
  /// Needs a current GL 4.5 context.
  static Status Create(int maxVertices, std::unique_ptr<InteropMesh>* out);
  ~InteropMesh();
  InteropMesh(const InteropMesh&) = delete;
  InteropMesh& operator=(const InteropMesh&) = delete;

  struct DevicePointers {
    float* positions = nullptr;  // 3 floats per vertex, device memory
    float* normals = nullptr;
    int capacity = 0;            // vertices
  };
  /// Maps the buffers for CUDA (cudaGraphicsMapResources on the default stream). Fails with one line in a
  /// build without CUDA or on a machine without a GPU.
  Status Map(DevicePointers* out);
  /// Unmaps; `vertexCount` vertices (a multiple of 3) were written.
  Status Unmap(int vertexCount);
  /// Host path into the same buffers (tests, and a CPU backend that wants to reuse them).
  Status Upload(const float* positions, const float* normals, int vertexCount);

  uint32_t PositionBuffer() const { return m_positions; }
  uint32_t NormalBuffer() const { return m_normals; }
  int VertexCount() const { return m_count; }
  int Capacity() const { return m_capacity; }

 private:
  InteropMesh() = default;
  uint32_t m_positions = 0, m_normals = 0;
  int m_count = 0, m_capacity = 0;
  void* m_resources[2] = {nullptr, nullptr};  // cudaGraphicsResource_t when built with CUDA
  bool m_mapped = false;
};

}  // namespace sphxr::render
