#pragma once
// DFSPH's rules, read through its row of the solver table (solver_table.cpp); its constants:
// dfsph_constants.h.
#include <array>
#include <cstdint>

#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {

/// The step follows the flow (Bender & Koschier 2017, sec. 5): no particle, fluid or paddle, moves more
/// than cfl * h per step. The pressure is implicit, so neither the sound speed nor the acceleration
/// limits it; the explicit viscosity still does.
float DfsphStableDt(const StableDtInput& in);
/// DfsphSolver's arrays (dfsph.h): a kernel gradient per neighbour slot (12; on the CPU lane-blocked, in
/// batches of 16 slots: PairCacheStride), the boundary terms (16), factor, increment, neighbour count and
/// the two stiffnesses (20), the step's start velocity (16) and the error terms (8).
int64_t DfsphBytes(int64_t neighbourSlots);

/// Its statistics: both solves' iterations and the mean errors they reached.
inline constexpr std::array<SolveColumn, 4> kDfsphColumns = {{
    {"density_iterations", &SolveReport::densityIterations, nullptr},
    {"divergence_iterations", &SolveReport::divergenceIterations, nullptr},
    {"solver_density_error", nullptr, &SolveReport::densityError},
    {"solver_divergence_error", nullptr, &SolveReport::divergenceError},
}};

}  // namespace sphxr::sim
