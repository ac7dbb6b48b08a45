#pragma once
// WCSPH's rules, read through its row of the solver table (solver_table.cpp).
#include <cstdint>

#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {

/// The acoustic CFL condition with the fastest particle or paddle point (Monaghan 1992; Becker &
/// Teschner 2007, sec. 5: nothing moves more than cfl * h per step), the force condition (a particle
/// moves at most ~h/16 per step under its acceleration) and the viscosity's limit.
float WcsphStableDt(const StableDtInput& in);
/// No arrays of its own: its stages are the shared ones.
int64_t WcsphBytes(int64_t neighbourSlots);

}  // namespace sphxr::sim
