#pragma once
// The per-particle stages of one WCSPH step, written once as host+device functors over plain views of
// raw pointers. backend_impl.h launches them with thrust on the OpenMP system (CPU backend) or the CUDA
// system (CUDA backend): the physics has exactly one source.
//
// Step (Becker & Teschner 2007, "Weakly compressible SPH for free surface flows"):
//   1. cells:     Morton code of each fluid particle's cell                  (Huang et al. 2013, §3.1)
//   2. sort:      stable radix/merge sort by code; gather every field         (fields.h list)
//   3. grid:      cellStart/cellEnd per cell from the sorted codes
//   4. density:   rho_i = sum_j m W_ij + sum_b Psi_b W_ib                     (Akinci et al. 2012, eq. 4-5)
//                 or, under solver.density delta_sph, integrated from d rho_i/dt (continuity equation with
//                 density diffusion, stages/density_diffusion.h)
//                 p_i = B ((rho_i/rho0)^gamma - 1), clamped at 0             (B&T 2007, eq. 7)
//   5. forces:    a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) gradW_ij  (B&T 2007, eq. 6 and 10)
//                       -sum_b Psi_b (s (p_i + p_b)/rho_i^2 + Pi_ib) gradW_ib (Akinci et al. 2012, eq. 10-11, in the
//                             symmetric form; p_b = max(p_i, Shepard average of p around i); s: flat-wall
//                             gradient consistency, sampling.h)
//                       + g
//                 Pi_ij = -2 alpha c h min(v_ij.x_ij, 0) / ((|x_ij|^2 + 0.01 h^2)(rho_i + rho_j))  (Monaghan 1992)
//   6. integrate: symplectic Euler v += dt a, x += dt v; particles leaving the domain are clamped back
//                 and counted.
//
// One header per stage, in the order of a step (the CPU's SIMD forms are under cpu/):
#include "stages/views.h"      // FluidView, GridView, NeighbourList, Physics, ForEachInCells
#include "stages/grid.h"       // 1, 3: cell codes, cell ranges
#include "stages/reuse.h"      // 3b: activity, the compacted list
#include "stages/walls.h"      // 3c: the walls' volumes and own pressure
#include "stages/density.h"    // 4: density, Tait pressure
#include "stages/density_diffusion.h"  // 4b: delta_sph, the continuity equation with density diffusion
#include "stages/forces.h"     // 5: pressure, viscosity, gravity
#include "stages/clamp.h"      // 6: the domain and obstacle clamps, and where they caught a particle
#include "stages/integrate.h"  // 6: symplectic Euler, the clamps, the step's statistics
#include "stages/settle.h"     // FIRE, before a run
