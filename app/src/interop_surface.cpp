#include "interop_surface.h"

#include <algorithm>

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

int64_t InteropCapacity(int64_t capacity, const sim::SurfaceWriteReport& last) {
  constexpr int64_t kMaxVertices = int64_t{1} << 26;
  constexpr int64_t kLeast = 3 * 4096;
  if (capacity >= kLeast && !(last.vertices > capacity)) return capacity;
  // Geometric growth, as the solver's own buffer (docs/dev/surface.md): O(log) re-creations, each logged.
  int64_t grown = std::min(kMaxVertices, std::max<int64_t>({last.vertices + last.vertices / 4, capacity + capacity / 2, kLeast}));
  return grown - grown % 3;
}

}  // namespace sphxr::app
