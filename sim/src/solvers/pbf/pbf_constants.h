#pragma once
// Position-based fluids' own constants (Macklin & Müller 2013 [MM13]), computed once from the scene by
// PbfSolver::Init and passed by value into its stages (pbf_stages.h) beside the shared Physics.
#include "sphxr/sim/params.h"
#include "stages/views.h"

namespace sphxr::sim {

struct PbfConstants {
  int iterations;      // Jacobi iterations of the density constraint a step
  float relaxation;    // epsilon, absolute (the relative scene value times the rest lattice's sum)
  float corrK;         // m^2: k over the rest lattice's sum |grad C|^2 (s_corr enters beside lambda)
  int corrN;
  float invCorrW;      // 1 / W(dq)
  float xsph;
  float vorticity;     // m/s, vorticity confinement's epsilon (0: off)
  float maxSpeed;
  float contact;       // m: the collision response's distance beyond the clamp box (the particle radius,
                       // half a spacing from a face, less the clamp's inset)
  int substeps;        // steps a displayed frame
  float margin;        // m: the neighbour lists' skin beyond the support (0: lists every step)
  float halfMargin2;   // m^2: (margin / 2)^2, the displacement since the lists that rebuilds them
  int skinCapacity;    // list slots a particle within the support plus the margin
};

/// The constants of `scene` (pbf_rules.cpp: built with the rest of the library, so their arithmetic
/// does not depend on the backend's compile flags).
PbfConstants MakePbfConstants(const SceneSetup& scene, const Physics& physics);

}  // namespace sphxr::sim
