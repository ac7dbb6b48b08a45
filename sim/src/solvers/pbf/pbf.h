#pragma once
// Position-based fluids (Macklin & Müller, "Position Based Fluids", ACM TOG 32(4), SIGGRAPH 2013
// [MM13]): the real-time solver. A fixed number of Jacobi iterations of the density constraint on
// predicted positions per step, so a step costs the same at any speed and the water can advance by
// one displayed frame per step (docs/design/pbf.md). The stages: solvers/pbf/pbf_stages.h.
#include <thrust/functional.h>

#include "solvers/pbf/pbf_stages.h"
#include "solvers/step_context.h"

namespace sphxr::sim {

template <class Traits>
class PbfSolver final : public PressureSolver<Traits> {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  /// Its constants from the scene (pbf_constants.h).
  void Init(const SceneSetup& scene, const Physics& physics) override { m_c = MakePbfConstants(scene, physics); }

  /// 1. predict: v* = v + dt g, x* = x + dt v* (before the grid: it is built at x*)     [MM13 alg. 1]
  void BeforeGrid(const FluidView& fluid, const Physics& ph, float dt) override {
    this->Device().ForEach(fluid.count, PbfPredictStage{fluid, ph, m_c, dt});
  }

  Status Step(StepContext<Traits>& ctx) override {
    const Physics& ph = ctx.physics;
    ctx.computing = ctx.n;
    Size(ctx.n);
    // 2. the neighbour lists at x* (the density stage; its Tait pressure is not used)
    ctx.Density();
    SPHXR_TRY(ctx.Lap(Stage::kDensity));
    // 3. pbf_iterations Jacobi iterations of the density constraint                 [MM13 eq. 9-13]
    const NeighbourList list = ctx.Neighbours();
    const PbfView view = View(ph.maxNeighbours);
    ctx.Device().Fill(m_lambdaSum, 0.0f);
    for (int k = 0; k < m_c.iterations; ++k) {
      ctx.Launch().ForEach(ctx.n, 64, PbfLambdaStage{ctx.grid, ctx.fluid, list, ph, m_c, view});
      ctx.Launch().ForEach(ctx.n, 64, PbfCorrectStage{ctx.grid, ctx.fluid, list, ph, m_c, view});
      ctx.Map(PbfApplyStage{ctx.fluid, ph, m_c, view});
    }
    ctx.report.densityIterations = m_c.iterations;
    const double residual =
        ctx.Device().TransformReduce(ctx.n, PbfResidual{ctx.fluid, ph.invRestDensity}, 0.0, thrust::plus<double>());
    ctx.report.densityError = ctx.n > 0 ? static_cast<float>(residual / ctx.n) : 0.0f;
    SPHXR_TRY(ctx.Lap(Stage::kPressure));
    // 4. velocities from the position change, the clamps, the pressure estimate            [MM13 alg. 1]
    ctx.Map(PbfFinishStage{ctx.fluid, ph, m_c, view, ctx.dt, ctx.BodyPressureTerm()});
    // 5. XSPH viscosity                                                                   [MM13 eq. 17]
    if (m_c.xsph > 0.0f) {
      ctx.Launch().ForEach(ctx.n, 64, PbfXsphStage{ctx.grid, ctx.fluid, list, ph, m_c, view});
      ctx.Map(PbfAddVelocityChangeStage{ctx.fluid, m_c, view});
    }
    // 5b. vorticity confinement, when the scene asks for it                            [MM13 eq. 15-16]
    if (m_c.vorticity > 0.0f) {
      if (m_vorticity.size() != static_cast<size_t>(ctx.n)) m_vorticity.resize(static_cast<size_t>(ctx.n));
      ctx.Launch().ForEach(ctx.n, 64, PbfVorticityStage{ctx.grid, ctx.fluid, list, ph, Raw(m_vorticity)});
      ctx.Launch().ForEach(ctx.n, 64,
                           PbfConfinementStage{ctx.grid, ctx.fluid, list, ph, m_c, view, Raw(m_vorticity), ctx.dt});
      ctx.Map(PbfAddVelocityChangeStage{ctx.fluid, m_c, view});
    }
    SPHXR_TRY(ctx.Lap(Stage::kIntegrate));
    // 6. the fluid's force on the paddles: the impulse of the corrections their particles caused
    if (ctx.HasBodies()) {
      ctx.BodyReaction(1.0f, /*viscous=*/false);
      SPHXR_TRY(ctx.Lap(Stage::kBodies));
    }
    // 7. probes, on the state the step ends in
    if (ctx.HasProbes()) {
      ctx.Probes();
      SPHXR_TRY(ctx.Lap(Stage::kProbes));
    }
    // 8. push the fluid out of the paddles at their end-of-step pose
    if (ctx.HasBodies()) {
      ctx.PushOut();
      SPHXR_TRY(ctx.Lap(Stage::kBodies));
    }
    return Status::Ok();
  }

 private:
  /// Whether the backend's launcher runs the SIMD passes that keep the lambda pass's pair terms (the
  /// CPU's, solvers/pbf/pbf_simd.h); the others recompute them and need no pair array.
  static constexpr bool kPairCache = kLauncherPairCache<Traits>;

  void Size(int n) {
    const size_t count = static_cast<size_t>(n);
    if (m_lambda.size() == count) return;
    m_lambda.resize(count);
    m_lambdaSum.resize(count);
    m_delta.resize(count);
    m_boundaryGrad.resize(count);
    if constexpr (kPairCache) m_ownCorrection.resize(count);
  }
  PbfView View(int maxNeighbours) {
    PbfView v{Raw(m_lambda), Raw(m_lambdaSum), Raw(m_delta), Raw(m_boundaryGrad), nullptr, nullptr, 0};
    if constexpr (kPairCache) {
      v.pairStride = PairCacheStride(maxNeighbours);
      m_pairGrad.resize(m_lambda.size() * static_cast<size_t>(v.pairStride));
      v.pairGrad = Raw(m_pairGrad);
      v.ownCorrection = Raw(m_ownCorrection);
    }
    return v;
  }

  PbfConstants m_c{};
  Vector<float> m_lambda, m_lambdaSum;
  Vector<Vec4> m_delta, m_boundaryGrad;
  Vector<float> m_pairGrad;        // the CPU's pair cache (PbfView::pairGrad)
  Vector<Vec4> m_ownCorrection;
  Vector<Vec4> m_vorticity;        // omega_i, w |omega_i| (vorticity confinement only)
};

}  // namespace sphxr::sim
