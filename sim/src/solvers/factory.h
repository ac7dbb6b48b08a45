#pragma once
// The solvers' factory over a backend's Traits: one line per row of the solver table (solver_table.cpp).
#include <memory>

#include "solvers/dfsph/dfsph.h"
#include "solvers/pbf/pbf.h"
#include "solvers/wcsph/wcsph.h"

namespace sphxr::sim {

template <class Traits>
std::unique_ptr<PressureSolver<Traits>> MakePressureSolver(SolverMethod method) {
  switch (method) {
    case SolverMethod::kWcsph: return std::make_unique<WcsphSolver<Traits>>();
    case SolverMethod::kDfsph: return std::make_unique<DfsphSolver<Traits>>();
    case SolverMethod::kPbf: return std::make_unique<PbfSolver<Traits>>();
  }
  return nullptr;
}

}  // namespace sphxr::sim
