#pragma once
// The one list of per-particle fields of the fluid. Resize, reorder after the neighbour sort,
// host/device copies and export all iterate this list (via SPHXR_FLUID_FIELDS), so a field added here
// can never be forgotten by the sort. Columns: type, name, what it holds.
//
// Hot fields (read in the 27-cell loops) come first; `id` is cold (read by export and tests only).
// Bytes per fluid particle in these fields: 16+16+16+4+4+4+4+4 = 68.
#include <cstdint>
#include <vector>

#include "sphxr/sim/vec.h"

#define SPHXR_FLUID_FIELDS(X)                                                   \
  X(::sphxr::sim::Vec4, position)     /* m; w = 1 near a wall (density stage) */ \
  X(::sphxr::sim::Vec4, velocity)     /* m/s; w unused                      */ \
  X(::sphxr::sim::Vec4, acceleration) /* m/s^2 of the last force stage      */ \
  X(float, density)                   /* kg/m^3, summation density          */ \
  X(float, pressure)                  /* Pa, Tait equation of state         */ \
  X(float, pressureTerm)              /* p / rho^2, for the force stage     */ \
  X(int32_t, idle)                    /* reuse idle count IC: -1 active     */ \
  X(uint32_t, id)                     /* stable particle identity           */

namespace sphxr::sim {

/// Host copy of every fluid field, in the solver's current (sorted) order.
struct HostFluid {
#define SPHXR_DECLARE_FIELD(type, name) std::vector<type> name;
  SPHXR_FLUID_FIELDS(SPHXR_DECLARE_FIELD)
#undef SPHXR_DECLARE_FIELD

  size_t size() const { return position.size(); }
  void resize(size_t n) {
#define SPHXR_RESIZE_FIELD(type, name) name.resize(n);
    SPHXR_FLUID_FIELDS(SPHXR_RESIZE_FIELD)
#undef SPHXR_RESIZE_FIELD
  }
};

/// Static boundary particles (Akinci et al. 2012): position and the volume-weighted mass Psi = rho0 * V_b.
struct HostBoundary {
  std::vector<Vec4> position;  // w = Psi (kg)
  std::vector<float> viscosity;  // artificial viscosity alpha of the wall this particle samples
  std::vector<float> invReference;  // 1 / sum_f W_bf over the rest lattice filling the tank (0: no reference)
  size_t size() const { return position.size(); }
};

}  // namespace sphxr::sim
