#include "interop_surface.h"

namespace sphxr::app {

const render::InteropMesh* InteropSurface::Update(SimWorker& worker, const SimSnapshot& snap) {
  if (!snap.surfaceOnDevice) return nullptr;
  if (snap.surfaceBuild > m_written) {
    uint64_t build = 0;
    if (Status s = worker.WriteSurfaceInto(&m_mesh, &build); !s) {
      worker.FallBackToHostCopy(s.message());
      m_written = 0;
      return nullptr;
    }
    if (build == 0) return nullptr;  // the solver was replaced and has built nothing yet
    m_written = build;               // the newest build: at least the snapshot's
  }
  return m_mesh && m_mesh->Written() ? m_mesh.get() : nullptr;
}

void InteropSurface::Reset() {
  m_mesh.reset();
  m_written = 0;
}

}  // namespace sphxr::app
