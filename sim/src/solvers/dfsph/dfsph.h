#pragma once
// Divergence-free SPH (Bender & Koschier 2015, 2017 [BK17]): the accurate solver, whose step follows the
// flow speed instead of the sound speed. Two Jacobi solves per step, on the velocities: the divergence
// (before the non-pressure forces) and the density (after them). The stages: solvers/dfsph/dfsph_stages.h.
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
      ctx.Device().Resize(m_pairGrad, floats);
    } else {
      ctx.Device().Resize(m_grad, n * static_cast<size_t>(list.maxNeighbours));
    }
    if (m_boundary.size() != n) {
      DeviceOps<Traits>& device = ctx.Device();
      device.Resize(m_boundary, n);
      device.Resize(m_factor, n);
      device.Resize(m_neighbours, n);
      device.Resize(m_delta, n);
      device.Resize(m_error, n);
      device.Resize(m_velocityStart, n);
      device.Resize(m_kappa, n);
      device.Resize(m_kappaV, n);
    }
    ctx.Launch().ForEach(ctx.n, 64, DfsphFactorStage{ctx.grid, ctx.fluid, list, ctx.physics, View()});
  }

  /// Jacobi iterations of one solve until its mean residual is below `tolerance` (after at least
  /// `minIterations`) or `maxIterations` were taken. The loop's decision is taken on the device
  /// (DfsphSolveDecideStage); the host reads it every kCheckEvery iterations, and the iterations
  /// launched past the end do nothing (UntilSolved), so the result is the same for any kCheckEvery.
  Result Solve(StepContext<Traits>& ctx, bool density, int minIterations, int maxIterations, float tolerance) {
    const int n = ctx.n;
    const NeighbourList list = ctx.Neighbours();
    const DfsphView view = View();
    const float scale = density ? 1.0f / ctx.dt : 1.0f;
    DeviceOps<Traits>& device = ctx.Device();
    device.Fill(density ? m_kappa : m_kappaV, 0.0f);
    device.Resize(m_state, 1);
    DfsphSolveState* state = Raw(m_state);
    device.ForEach(1, DfsphSolveResetStage{state});
    const DfsphPredictStage predict{ctx.grid, ctx.fluid, list, ctx.physics, view, ctx.dt, density};
    const DfsphCorrectStage correct{ctx.grid, ctx.fluid, list, ctx.physics, view, scale, density};
    DfsphSolveState last{};
    for (int k = 1;; ++k) {
      if constexpr (kCheckEvery == 1) {
        ctx.Launch().ForEach(n, 64, predict);
      } else {
        ctx.Launch().ForEach(n, 64, UntilSolved<DfsphPredictStage>{state, predict});
      }
      device.SumInto(Raw(m_error), n, &state->sum);
      device.ForEach(1, DfsphSolveDecideStage{state, n, tolerance, minIterations, maxIterations});
      if (k % kCheckEvery == 0) {
        last = device.Read(m_state, 0);
        if (last.done) break;
      }
      if constexpr (kCheckEvery == 1) {
        ctx.Launch().ForEach(n, 64, correct);
      } else {
        ctx.Launch().ForEach(n, 64, UntilSolved<DfsphCorrectStage>{state, correct});
      }
    }
    return Result{last.iterations, last.error};
  }

  DfsphView View() {
    return DfsphView{Raw(m_kappa),      Raw(m_kappaV), Raw(m_grad),  Raw(m_boundary),      Raw(m_factor),
                     Raw(m_neighbours), Raw(m_delta),  Raw(m_error), Raw(m_velocityStart), Raw(m_pairGrad),
                     m_pairStride};
  }

  /// Whether the launcher's SIMD passes keep G_ij lane-blocked (the CPU's, solvers/dfsph/dfsph_simd.h) in place of the
  /// scalar stages' Vec3 a slot.
  static constexpr bool kPairCache = kLauncherPairCache<Traits>;
  /// How often the host reads a solve's state: every iteration where that read costs nothing (the
  /// CPU's launcher, whose SIMD passes then need no gate), else the launcher's period.
  static constexpr int kCheckEvery = kLauncherSolveCheckEvery<Traits>;

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
  Vector<DfsphSolveState> m_state;  // the running solve's (one)
};

}  // namespace sphxr::sim
