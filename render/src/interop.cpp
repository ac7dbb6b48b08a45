#include "sphxr/render/interop.h"

#include <epoxy/gl.h>

#if SPHXR_HAVE_CUDA
#include <cuda_gl_interop.h>
#include <cuda_runtime_api.h>
#endif

#include "sphxr/common/log.h"

namespace sphxr::render {

Status InteropMesh::Create(int maxVertices, std::unique_ptr<InteropMesh>* out) {
  out->reset();
  if (maxVertices <= 0 || maxVertices > (1 << 26)) {
    return Status::Error(Format("interop mesh of %d vertices: must be from 1 to %d", maxVertices, 1 << 26));
  }
  std::unique_ptr<InteropMesh> m(new InteropMesh());
  m->m_capacity = maxVertices;
  const GLsizeiptr bytes = static_cast<GLsizeiptr>(maxVertices) * 3 * sizeof(float);
  glCreateBuffers(1, &m->m_positions);
  glNamedBufferStorage(m->m_positions, bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateBuffers(1, &m->m_normals);
  glNamedBufferStorage(m->m_normals, bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
  const GLuint nothing[4] = {0, 1, 0, 0};  // glDrawArraysIndirect's {count, instanceCount, first, baseInstance}
  glCreateBuffers(1, &m->m_drawCommand);
  glNamedBufferStorage(m->m_drawCommand, sizeof(nothing), nothing, GL_DYNAMIC_STORAGE_BIT);
#if SPHXR_HAVE_CUDA
  int devices = 0;
  if (cudaGetDeviceCount(&devices) == cudaSuccess && devices > 0) {
    const GLuint buffers[kBuffers] = {m->m_positions, m->m_normals, m->m_drawCommand};
    for (int i = 0; i < kBuffers; ++i) {
      cudaGraphicsResource_t resource = nullptr;
      const cudaError_t e = cudaGraphicsGLRegisterBuffer(&resource, buffers[i], cudaGraphicsRegisterFlagsWriteDiscard);
      if (e != cudaSuccess) {
        return Status::Error(std::string("CUDA-GL interop: cudaGraphicsGLRegisterBuffer failed: ") + cudaGetErrorString(e) +
                             " (is the GL context on the CUDA device?)");
      }
      m->m_resources[i] = resource;
    }
  }
#endif
  *out = std::move(m);
  return Status::Ok();
}

InteropMesh::~InteropMesh() {
#if SPHXR_HAVE_CUDA
  for (void* r : m_resources) {
    if (r) cudaGraphicsUnregisterResource(static_cast<cudaGraphicsResource_t>(r));
  }
#endif
  glDeleteBuffers(1, &m_positions);
  glDeleteBuffers(1, &m_normals);
  glDeleteBuffers(1, &m_drawCommand);
}

Status InteropMesh::Map(DevicePointers* out) {
#if SPHXR_HAVE_CUDA
  if (!m_resources[0]) return Status::Error("CUDA-GL interop: no CUDA device registered these buffers");
  cudaGraphicsResource_t resources[kBuffers];
  for (int i = 0; i < kBuffers; ++i) resources[i] = static_cast<cudaGraphicsResource_t>(m_resources[i]);
  if (cudaError_t e = cudaGraphicsMapResources(kBuffers, resources, 0); e != cudaSuccess) {
    return Status::Error(std::string("CUDA-GL interop: map failed: ") + cudaGetErrorString(e));
  }
  void* pointers[kBuffers] = {nullptr, nullptr, nullptr};
  for (int i = 0; i < kBuffers; ++i) {
    size_t bytes = 0;
    if (cudaError_t e = cudaGraphicsResourceGetMappedPointer(&pointers[i], &bytes, resources[i]); e != cudaSuccess) {
      cudaGraphicsUnmapResources(kBuffers, resources, 0);
      return Status::Error(std::string("CUDA-GL interop: mapped pointer: ") + cudaGetErrorString(e));
    }
  }
  out->positions = static_cast<float*>(pointers[0]);
  out->normals = static_cast<float*>(pointers[1]);
  out->drawCommand = static_cast<uint32_t*>(pointers[2]);
  out->capacity = m_capacity;
  m_mapped = true;
  return Status::Ok();
#else
  (void)out;
  return Status::Error("CUDA-GL interop: this build has no CUDA backend (meshes are uploaded from the host)");
#endif
}

Status InteropMesh::Unmap() {
#if SPHXR_HAVE_CUDA
  if (!m_mapped) return Status::Error("interop mesh: Unmap without Map");
  cudaGraphicsResource_t resources[kBuffers];
  for (int i = 0; i < kBuffers; ++i) resources[i] = static_cast<cudaGraphicsResource_t>(m_resources[i]);
  if (cudaError_t e = cudaGraphicsUnmapResources(kBuffers, resources, 0); e != cudaSuccess) {
    return Status::Error(std::string("CUDA-GL interop: unmap failed: ") + cudaGetErrorString(e));
  }
  m_mapped = false;
  m_written = true;
  return Status::Ok();
#else
  return Status::Error("CUDA-GL interop: this build has no CUDA backend");
#endif
}

Status InteropMesh::Upload(const float* positions, const float* normals, int vertexCount) {
  if (vertexCount < 0 || vertexCount > m_capacity) {
    return Status::Error(Format("interop mesh: %d vertices, capacity %d", vertexCount, m_capacity));
  }
  const GLsizeiptr bytes = static_cast<GLsizeiptr>(vertexCount) * 3 * sizeof(float);
  if (bytes > 0) {
    glNamedBufferSubData(m_positions, 0, bytes, positions);
    glNamedBufferSubData(m_normals, 0, bytes, normals);
  }
  const GLuint command[4] = {static_cast<GLuint>(vertexCount), 1, 0, 0};
  glNamedBufferSubData(m_drawCommand, 0, sizeof(command), command);
  m_written = true;
  return Status::Ok();
}

}  // namespace sphxr::render
