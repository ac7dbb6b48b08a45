#pragma once
// Divergence-free SPH (Bender & Koschier 2015, 2017 [BK17]): the accurate solver, whose step follows the
// flow speed instead of the sound speed. Two Jacobi solves per step, on the velocities: the divergence
// (before the non-pressure forces) and the density (after them). The stages: solvers/dfsph/dfsph_stages.h.
#include <thrust/fill.h>
#include <thrust/reduce.h>

#include "solvers/dfsph/dfsph_constants.h"
#include "solvers/dfsph/dfsph_stages.h"
#include "solvers/step_context.h"

namespace sphxr::sim {

template <class Traits>
class DfsphSolver final : public PressureSolver<Traits> {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  /// Its constants from the scene (dfsph_constants.h).
  void Init(const SceneSetup& scene, const Physics& physics) override { m_c = MakeDfsphConstants(scene, physics); }

  Status Step(StepContext<Traits>& ctx) override {
    const Physics& ph = ctx.physics;
    ctx.computing = ctx.n;
    // 1. density rho_i = sum_j m W_ij + sum_b Psi_b W_ib and the neighbour lists (its Tait pressure
    //    is not used)                                                                     [BK17 eq. 1]
    ctx.Density();
    SPHXR_TRY(ctx.Lap(Stage::kDensity));
    // 2. factor alpha_i, the cached kernel gradients and the boundary terms                [BK17 eq. 11]
    Prepare(ctx);
    SPHXR_TRY(ctx.Lap(Stage::kDensity));
    // 3. divergence-free solve on the velocities at the start of the step        [BK17 §4.2, alg. 2]
    if (m_c.maxDivergenceIterations > 0) {
      const Result r =
          Solve(ctx, false, m_c.minDivergenceIterations, m_c.maxDivergenceIterations, m_c.divergenceTolerance);
      ctx.report.divergenceIterations = r.iterations;
      ctx.report.divergenceError = r.error;
    }
    // 4. the non-pressure forces: the force stage with every pressure zero (viscosity, gravity)
    ctx.Map(DfsphZeroPressureStage{ctx.fluid});
    SPHXR_TRY(ctx.Lap(Stage::kDivergence));
    ctx.Forces();
    SPHXR_TRY(ctx.Lap(Stage::kForces));
    // 5. kick v* = v + dt a, then the density-invariance solve on v*              [BK17 §4.1, alg. 3]
    ctx.Map(DfsphKickStage{ctx.fluid, View(), ctx.dt});
    const Result r = Solve(ctx, true, m_c.minIterations, m_c.maxIterations, m_c.densityTolerance);
    ctx.report.densityIterations = r.iterations;
    ctx.report.densityError = r.error;
    ctx.report.densityCapped = r.iterations >= m_c.maxIterations && r.error > m_c.densityTolerance;
    SPHXR_TRY(ctx.Lap(Stage::kPressure));
    // 6. the step's pressure (into the bodies' reaction term), acceleration and, without probes, the drift
    const bool probes = ctx.HasProbes();
    ctx.Map(DfsphFinishStage{ctx.fluid, ph, View(), ctx.dt, ctx.BodyPressureTerm(), /*drift=*/!probes});
    // 7. the fluid's force on the paddles: the solves' own p_i / rho_i^2, no flat-wall correction (the
    //    solve is consistent with its own boundary gradients)
    if (ctx.HasBodies()) {
      ctx.BodyReaction(1.0f);
      SPHXR_TRY(ctx.Lap(Stage::kBodies));
    }
    // 8. probes on the state at the start of the step, then its drift
    if (probes) {
      ctx.Probes();
      SPHXR_TRY(ctx.Lap(Stage::kProbes));
      ctx.Drift();
    }
    SPHXR_TRY(ctx.Lap(Stage::kIntegrate));
    // 9. push the fluid out of the paddles at their end-of-step pose
    if (ctx.HasBodies()) {
      ctx.PushOut();
      SPHXR_TRY(ctx.Lap(Stage::kBodies));
    }
    return Status::Ok();
  }

 private:
  struct Result {
    int iterations = 0;
    float error = 0.0f;  // mean residual (fraction) after the last correction
  };

  /// Sizes the arrays for this step's particles and computes the factor and boundary terms.
  void Prepare(StepContext<Traits>& ctx) {
    const NeighbourList list = ctx.Neighbours();
    const size_t n = static_cast<size_t>(ctx.n);
    if constexpr (kPairCache) {
      m_pairStride = PairCacheStride(list.maxNeighbours);
      const size_t floats = n * static_cast<size_t>(m_pairStride);
      if (m_pairGrad.size() != floats) m_pairGrad.resize(floats);
    } else {
      const size_t slots = n * static_cast<size_t>(list.maxNeighbours);
      if (m_grad.size() != slots) m_grad.resize(slots);
    }
    if (m_boundary.size() != n) {
      m_boundary.resize(n);
      m_factor.resize(n);
      m_neighbours.resize(n);
      m_delta.resize(n);
      m_error.resize(n);
      m_velocityStart.resize(n);
      m_kappa.resize(n);
      m_kappaV.resize(n);
    }
    ctx.Launch().ForEach(ctx.n, 64, DfsphFactorStage{ctx.grid, ctx.fluid, list, ctx.physics, View()});
  }

  /// Jacobi iterations of one solve until its mean residual is below `tolerance` (after at least
  /// `minIterations`) or `maxIterations` were taken.
  Result Solve(StepContext<Traits>& ctx, bool density, int minIterations, int maxIterations, float tolerance) {
    const int n = ctx.n;
    const NeighbourList list = ctx.Neighbours();
    const DfsphView view = View();
    const float scale = density ? 1.0f / ctx.dt : 1.0f;
    auto& kappa = density ? m_kappa : m_kappaV;
    thrust::fill(Traits::Policy(), kappa.begin(), kappa.end(), 0.0f);
    Result result;
    for (;;) {
      ctx.Launch().ForEach(n, 64, DfsphPredictStage{ctx.grid, ctx.fluid, list, ctx.physics, view, ctx.dt, density});
      const uint64_t sum = thrust::reduce(Traits::Policy(), m_error.begin(), m_error.end(), uint64_t{0});
      result.error = n > 0 ? static_cast<float>(static_cast<double>(sum) / kErrorScale / n) : 0.0f;
      if ((result.error <= tolerance && result.iterations >= minIterations) || result.iterations >= maxIterations) break;
      ctx.Launch().ForEach(n, 64, DfsphCorrectStage{ctx.grid, ctx.fluid, list, ctx.physics, view, scale, density});
      ++result.iterations;
    }
    return result;
  }

  DfsphView View() {
    return DfsphView{Raw(m_kappa),      Raw(m_kappaV), Raw(m_grad),  Raw(m_boundary),      Raw(m_factor),
                     Raw(m_neighbours), Raw(m_delta),  Raw(m_error), Raw(m_velocityStart), Raw(m_pairGrad),
                     m_pairStride};
  }

  /// Whether the launcher's SIMD passes keep G_ij lane-blocked (the CPU's, solvers/dfsph/dfsph_simd.h) in place of the
  /// scalar stages' Vec3 a slot.
  static constexpr bool kPairCache = kLauncherPairCache<Traits>;

  DfsphConstants m_c{};
  Vector<Vec3> m_grad;       // G_ij a neighbour slot (the scalar stages)
  Vector<float> m_pairGrad;  // the same, lane-blocked (kPairCache)
  int m_pairStride = 0;
  Vector<Vec4> m_boundary;
  Vector<float> m_factor;
  Vector<int32_t> m_neighbours;
  Vector<float> m_delta;
  Vector<uint64_t> m_error;
  Vector<Vec4> m_velocityStart;
  Vector<float> m_kappa, m_kappaV;
};

}  // namespace sphxr::sim
