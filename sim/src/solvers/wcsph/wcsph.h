#pragma once
// Weakly compressible SPH (Becker & Teschner, "Weakly compressible SPH for free surface flows", SCA
// 2007), the paper's solver (Huang et al. 2013): the Tait equation of state, explicit pressure and
// viscosity forces, symplectic Euler at the acoustic CFL step; activity-based reuse, the walls' own
// density and delta-SPH are its options (its row of the solver table).
#include "solvers/step_context.h"

namespace sphxr::sim {

template <class Traits>
class WcsphSolver final : public PressureSolver<Traits> {
 public:
  /// No constants of its own: the Tait equation's are the shared Physics (the density stage's pressure).
  void Init(const SceneSetup& /*scene*/, const Physics& /*physics*/) override {}

  Status Step(StepContext<Traits>& ctx) override {
    const Physics& ph = ctx.physics;
    ctx.computing = ctx.n;
    // 1. activity: classify, compact the particles that compute (Huang et al. 2013, §3.3, eq. 5)
    if (ph.reuseEnabled) {
      ctx.Activity();
      SPHXR_TRY(ctx.Lap(Stage::kActivity));
    }
    // 2. the walls' own pressure (wall_density; docs/design/walls.md)
    ctx.WallPressure();
    // 3. density rho_i = sum_j m W_ij + sum_b Psi_b W_ib, Tait pressure (Akinci et al. 2012 eq. 4-5;
    //    B&T 2007 eq. 7)
    ctx.Density();
    SPHXR_TRY(ctx.Lap(Stage::kDensity));
    // 4. pressure and viscosity forces, gravity (B&T 2007 eq. 6, 10; Akinci et al. 2012 eq. 10-11)
    ctx.Forces();
    SPHXR_TRY(ctx.Lap(Stage::kForces));
    // 5. the fluid's force on the paddles (the reaction of 4's body terms, flat-wall corrected)
    if (ctx.HasBodies()) {
      ctx.BodyReaction(ph.bodyGradScale);
      SPHXR_TRY(ctx.Lap(Stage::kBodies));
    }
    // 6. probes, on the state at the start of the step
    if (ctx.HasProbes()) {
      ctx.Probes();
      SPHXR_TRY(ctx.Lap(Stage::kProbes));
    }
    // 7. symplectic Euler with the impulse hold's kick, the walls' contact, the clamps
    ctx.Integrate();
    // 8. delta_sph: the continuity equation with density diffusion at the drifted state (Molteni &
    //    Colagrossi 2009; Antuono et al. 2010; Fourtakas et al. 2019)
    if (ph.continuityDensity) ctx.DensityDiffusion();
    SPHXR_TRY(ctx.Lap(Stage::kIntegrate));
    // 9. push the fluid out of the paddles at their end-of-step pose
    if (ctx.HasBodies()) {
      ctx.PushOut();
      SPHXR_TRY(ctx.Lap(Stage::kBodies));
    }
    return Status::Ok();
  }
};

}  // namespace sphxr::sim
