#pragma once
// What a pressure solver reports of its step: one plain struct, by value from the solver's step to
// StepInfo::solve, the totals, the stats CSV, the panel and the Python module. Which of its fields a
// method fills, and their names, are the columns of its row of the solver table (SolverInfo::columns):
// a new statistic is one field here and one column in its row.
#include <cstdint>

namespace sphxr::sim {

struct SolveReport {
  int32_t densityIterations = 0;     // iterations of its density solve (PBF: its fixed count)
  int32_t divergenceIterations = 0;  // iterations of its divergence solve (DFSPH)
  float densityError = 0.0f;         // the density solve's mean compression at its end (fraction)
  float divergenceError = 0.0f;      // the divergence solve's mean compression rate times dt (fraction)
  bool densityCapped = false;        // the density solve stopped at solver.max_iterations above its tolerance
};

/// One statistic of a method: its name (the stats CSV's column, the panel's label) and the field of the
/// report it reads, an iteration count or a fraction (the panel shows fractions in %).
struct SolveColumn {
  const char* name;
  int32_t SolveReport::*count = nullptr;
  float SolveReport::*fraction = nullptr;
  double Value(const SolveReport& r) const {
    return count ? static_cast<double>(r.*count) : static_cast<double>(r.*fraction);
  }
};

}  // namespace sphxr::sim
