#pragma once
// Position-based fluids (Macklin & Müller, "Position Based Fluids", ACM TOG 32(4), SIGGRAPH 2013
// [MM13]): the real-time solver. A fixed number of Jacobi iterations of the density constraint on
// predicted positions per step, so a step costs the same at any speed and the water can advance by
// one displayed frame per step (docs/design/pbf.md). The stages: solvers/pbf/pbf_stages.h.
#include <thrust/functional.h>

#include <utility>

#include "solvers/pbf/pbf_stages.h"
#include "solvers/step_context.h"

namespace sphxr::sim {

template <class Traits>
class PbfSolver final : public PressureSolver<Traits> {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  /// Its constants from the scene (pbf_constants.h).
  void Init(const SceneSetup& scene, const Physics& physics) override {
    m_c = MakePbfConstants(scene, physics);
    m_reach = physics;
    m_reach.kernel = CubicSpline::Make(physics.kernel.H + m_c.margin);
    this->Device().Resize(m_gate, 1);
    this->Device().Fill(m_gate, 1);
    m_referenced = false;
  }

  /// 1. predict: v* = v + dt g, x* = x + dt v* (before the grid: it is built at x*), and with a skin
  ///    the check of every particle's displacement since the lists                         [MM13 alg. 1]
  void BeforeGrid(const FluidView& fluid, const Physics& ph, float dt) override {
    m_step = ph.step;
    m_frameTime += dt;
    const bool check = m_c.margin > 0.0f && m_referenced && m_reference.size() == static_cast<size_t>(fluid.count);
    this->Device().ForEach(fluid.count, PbfPredictStage{fluid, ph, m_c, dt, check ? Raw(m_reference) : nullptr, Raw(m_gate)});
  }

  /// The grid and the skin's lists once per displayed frame (its first substep), and again where the
  /// prediction's check or a re-sort outside the step asks (pbf_skin 0: every step, ungated).
  const int* GridGate(bool resorted) override {
    if (m_c.margin <= 0.0f) return nullptr;
    const bool frameStart = m_c.substeps <= 1 || (m_step - 1) % m_c.substeps == 0;
    if (resorted || frameStart || !m_referenced) this->Device().Fill(m_gate, 1);
    return Raw(m_gate);
  }

  /// The post-step stages (the diffuse particles) once per displayed frame, over the frame's time.
  float PostStepDt(float /*dt*/) override {
    return m_c.substeps <= 1 || m_step % m_c.substeps == 0 ? std::exchange(m_frameTime, 0.0f) : 0.0f;
  }

  Status Step(StepContext<Traits>& ctx) override {
    const Physics& ph = ctx.physics;
    ctx.computing = ctx.n;
    Size(ctx.n);
    // 2. the neighbour lists at x*: from the skin's (built with the grid), or the density stage's
    Lists(ctx);
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
      if (m_vorticity.size() != static_cast<size_t>(ctx.n)) this->Device().Resize(m_vorticity, static_cast<size_t>(ctx.n));
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

  /// Every particle's neighbours within the support at x*. With a skin: where the gate is open (the
  /// grid was just rebuilt), the lists within the support plus the margin and the positions they were
  /// built at, the gate then closed; every step, the pairs within the support picked from those lists.
  /// Without: the density stage's lists (its Tait pressure is not used).
  void Lists(StepContext<Traits>& ctx) {
    if (m_c.margin <= 0.0f) {
      ctx.Density();
      return;
    }
    const size_t n = static_cast<size_t>(ctx.n);
    const size_t slots = n * static_cast<size_t>(m_c.skinCapacity);
    if (m_skinIndex.size() != slots) this->Device().Resize(m_skinIndex, slots);
    if (m_skinCount.size() != n) this->Device().Resize(m_skinCount, n);
    if (m_reference.size() != n) this->Device().Resize(m_reference, n);
    const NeighbourList skin{Raw(m_skinIndex), Raw(m_skinCount), m_c.skinCapacity};
    const int* gate = Raw(m_gate);
    if (ctx.Launch().Launches(gate)) {
      ctx.ListsWithin(skin, m_reach, gate);
      ctx.Map(PbfReferenceStage{ctx.fluid, Raw(m_reference), gate});
      ctx.Device().Fill(m_gate, 0);
      m_referenced = true;
    }
    ctx.Launch().ForEach(ctx.n, 64, PbfNearListStage{ctx.fluid, skin, ctx.Neighbours(), ctx.physics.kernel.H2});
  }

  void Size(int n) {
    const size_t count = static_cast<size_t>(n);
    if (m_lambda.size() == count) return;
    this->Device().Resize(m_lambda, count);
    this->Device().Resize(m_lambdaSum, count);
    this->Device().Resize(m_delta, count);
    this->Device().Resize(m_boundaryGrad, count);
    if constexpr (kPairCache) this->Device().Resize(m_ownCorrection, count);
  }
  PbfView View(int maxNeighbours) {
    PbfView v{Raw(m_lambda), Raw(m_lambdaSum), Raw(m_delta), Raw(m_boundaryGrad), nullptr, nullptr, 0};
    if constexpr (kPairCache) {
      v.pairStride = PairCacheStride(maxNeighbours);
      this->Device().Resize(m_pairGrad, m_lambda.size() * static_cast<size_t>(v.pairStride));
      v.pairGrad = Raw(m_pairGrad);
      v.ownCorrection = Raw(m_ownCorrection);
    }
    return v;
  }

  PbfConstants m_c{};
  Physics m_reach{};                  // the physics with the kernel's support widened to the lists' reach
  Vector<uint32_t> m_skinIndex, m_skinCount;  // the skin's lists (m_c.skinCapacity slots a particle)
  Vector<Vec4> m_reference;           // every particle's position when the lists were built
  Vector<int> m_gate;                 // 1: rebuild the grid and the lists this step (GridGate)
  bool m_referenced = false;          // m_reference holds the last lists' positions
  int64_t m_step = 0;                 // the step's number (Physics::step): its place in the frame
  float m_frameTime = 0.0f;           // s: the frame's steps so far (PostStepDt)
  Vector<float> m_lambda, m_lambdaSum;
  Vector<Vec4> m_delta, m_boundaryGrad;
  Vector<float> m_pairGrad;        // the CPU's pair cache (PbfView::pairGrad)
  Vector<Vec4> m_ownCorrection;
  Vector<Vec4> m_vorticity;        // omega_i, w |omega_i| (vorticity confinement only)
};

}  // namespace sphxr::sim
