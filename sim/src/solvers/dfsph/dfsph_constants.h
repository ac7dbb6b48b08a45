#pragma once
// DFSPH's own constants (Bender & Koschier 2017), computed once from the scene by DfsphSolver::Init.
#include "sphxr/sim/params.h"
#include "stages/views.h"

namespace sphxr::sim {

struct DfsphConstants {
  float densityTolerance;       // mean compression (fraction) at which the density solve stops
  float divergenceTolerance;    // mean compression per step (fraction) at which the divergence solve stops
  int minIterations;
  int maxIterations;
  int minDivergenceIterations;
  int maxDivergenceIterations;  // 0: no divergence solve
};

/// The constants of `scene` (dfsph_rules.cpp).
DfsphConstants MakeDfsphConstants(const SceneSetup& scene, const Physics& physics);

}  // namespace sphxr::sim
