#pragma once
// Diffuse particles: spray, foam and air bubbles (Ihmsen, Akinci, Akinci, Teschner, "Unified spray, foam
// and air bubbles for particle-based fluids", The Visual Computer 28, 2012). The solver spawns them where
// the water traps air or breaks (solver.diffuse, docs/design/diffuse.md) and moves them after every
// step; they never act on the water. This is what a renderer reads (Solver::DownloadDiffuse).
#include <cstdint>
#include <vector>

#include "sphxr/sim/vec.h"

namespace sphxr::sim {

/// What a diffuse particle is, from the fluid particles around it (the paper's classification): few
/// (below solver.diffuse_spray_below): spray, ballistic; many (above solver.diffuse_bubble_above): an air
/// bubble, buoyant, dragged toward the water's velocity; between: foam, carried by the water.
enum class DiffuseKind : uint8_t { kSpray, kFoam, kBubble };

/// "spray", "foam", "bubble".
const char* DiffuseKindName(DiffuseKind kind);

/// The kind stored in a diffuse particle's velocity.w (0, 1, 2 as a float).
inline DiffuseKind DiffuseKindOf(const Vec4& velocity) {
  return velocity.w < 0.5f ? DiffuseKind::kSpray : (velocity.w < 1.5f ? DiffuseKind::kFoam : DiffuseKind::kBubble);
}

/// The diffuse particles of a solver, oldest first (the pool's order: when it is full, the oldest are
/// retired first).
struct HostDiffuse {
  std::vector<Vec4> position;  // m; w = the lifetime left, s (only foam ages)
  std::vector<Vec4> velocity;  // m/s; w = the kind (DiffuseKind) as a float
  int count = 0;               // == position.size() == velocity.size()

  void resize(int n) {
    position.resize(static_cast<size_t>(n));
    velocity.resize(static_cast<size_t>(n));
    count = n;
  }
};

}  // namespace sphxr::sim
