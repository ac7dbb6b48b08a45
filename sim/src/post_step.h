#pragma once
// Post-step stages: work that follows every step of every solver, on the state the step ends in, and
// reads the fluid without writing it (so the water is the same with them or without: diffuse particles
// today). The backend runs its list after the solver's step and the reduction (backend_impl.h
// PostSteps()); a new one is a member of the backend and one entry in that list. Each is timed as its
// own Stage.
#include <functional>

#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"
#include "stages/views.h"

namespace sphxr::sim {

/// What a post-step stage reads: the step's dt and physics, the grid's geometry (its fluid ranges are
/// those of the step's sort, from before the particles moved), the fluid where the step left it.
struct PostStepContext {
  float dt;
  const Physics& physics;
  GridView grid;
  FluidView fluid;                   // read only
  std::function<Status(Stage)> lap;  // ends a timed stage
};

class PostStepStage {
 public:
  virtual ~PostStepStage() = default;
  /// Whether it runs in this step (a stage the scene turned off costs nothing).
  virtual bool Active(const Physics& physics) const = 0;
  virtual Status Run(PostStepContext& ctx) = 0;
};

}  // namespace sphxr::sim
