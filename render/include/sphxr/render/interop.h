#pragma once
// A surface mesh that lives in OpenGL buffers and is written by CUDA in place (CUDA-GL interop), so a
// GPU backend's HPMC output reaches the screen without a host copy. Three buffers: positions, normals
// and a glDrawArraysIndirect command whose vertex count the writer fills on the device, so the count
// never reaches the host either; the renderer draws it with glDrawArraysIndirect. The GL side is always
// built; Map/Unmap exist only in builds with the CUDA backend (SPHXR_HAVE_CUDA) and need a GPU: on a
// machine without one they are compiled, not run. Upload fills the same three buffers from the host.
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
    uint32_t* drawCommand = nullptr;  // {count, instanceCount, first, baseInstance}, device memory
    int capacity = 0;            // vertices
  };
  /// Maps the buffers for CUDA (cudaGraphicsMapResources on the default stream). Fails with one line in a
  /// build without CUDA or on a machine without a GPU.
  Status Map(DevicePointers* out);
  /// Unmaps after the writer filled the buffers and the draw command.
  Status Unmap();
  /// Host path into the same buffers, the draw command included (tests, and a CPU backend that wants
  /// to reuse them).
  Status Upload(const float* positions, const float* normals, int vertexCount);

  uint32_t PositionBuffer() const { return m_positions; }
  uint32_t NormalBuffer() const { return m_normals; }
  /// The GL_DRAW_INDIRECT_BUFFER: 4 uint32 {vertex count, 1, 0, 0}; {0, 1, 0, 0} until written.
  uint32_t DrawCommandBuffer() const { return m_drawCommand; }
  /// The buffers hold a mesh (Unmap or Upload has run); its size is in the draw command only.
  bool Written() const { return m_written; }
  int Capacity() const { return m_capacity; }

 private:
  InteropMesh() = default;
  static constexpr int kBuffers = 3;  // positions, normals, draw command
  uint32_t m_positions = 0, m_normals = 0, m_drawCommand = 0;
  int m_capacity = 0;
  bool m_written = false;
  void* m_resources[kBuffers] = {nullptr, nullptr, nullptr};  // cudaGraphicsResource_t when built with CUDA
  bool m_mapped = false;
};

}  // namespace sphxr::render
