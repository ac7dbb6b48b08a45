#pragma once
// PBF's rules, read through its row of the solver table (solver_table.cpp); its constants:
// pbf_constants.h.
#include <array>
#include <cstdint>
#include <string>

#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {

/// No stability bound from the sound speed or the flow (Macklin & Müller 2013): pbf_substeps steps per
/// pbf_frame, the displayed frame; the viscosity is XSPH's.
float PbfStableDt(const StableDtInput& in);
/// PbfSolver's arrays (pbf.h): lambda and its sum over the step (8), the position corrections (16), the
/// boundary gradients (16); on the CPU the own terms (16) and the pair cache (12 a slot, in batches of
/// 16 slots: PairCacheStride). The step's start positions live in the acceleration field.
int64_t PbfBytes(int64_t neighbourSlots);
/// The neighbour lists' margin beyond the support (m): pbf_skin spacings (solver table's listMargin).
float PbfListMargin(const SolverParams& params);
/// The compression a column of water will keep at rest, when it is large (docs/design/pbf.md).
void PbfWarnAtStart(const SceneSetup& scene, float waterHeight);
/// pbf_substeps for `spacing` (PbfSubstepsForSpacing).
std::string PbfParamsForSpacing(const SolverParams& scene, float spacing, SolverParams* out);
/// The substeps a frame at `spacing` for a scene that takes `sceneSubsteps` at `sceneSpacing`: the
/// fewest that keep the step per spacing (dt / h) at most the scene's, within pbf_substeps' range [1, 16].
/// PBF's rest compression goes as g D dt^2 / (N h^2) (docs/design/pbf.md), so a coarser spacing keeps the
/// scene's compression and stability with fewer substeps, and a finer one needs more.
float PbfSubstepsForSpacing(float sceneSubsteps, float sceneSpacing, float spacing);

/// Its statistics: the iterations (a fixed count) and the constraint's mean residual after them.
inline constexpr std::array<SolveColumn, 2> kPbfColumns = {{
    {"density_iterations", &SolveReport::densityIterations, nullptr},
    {"solver_density_error", nullptr, &SolveReport::densityError},
}};

}  // namespace sphxr::sim
