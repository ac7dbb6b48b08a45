#pragma once
// Turning a SceneSetup into particles and a grid shape. Counting and sampling share one code path,
// so the counts used to refuse a scene are exactly what would be allocated.
#include <cstdint>
#include <vector>

#include "backend.h"
#include "kernel.h"
#include "sphxr/sim/params.h"

namespace sphxr::sim {

/// Fluid particles on a lattice of the rest spacing, first particle half a spacing inside each block
/// corner; points inside or within half a spacing of an obstacle are skipped. `out` may be null (count only).
int64_t SampleFluid(const SceneSetup& scene, std::vector<Vec4>* out);

/// Logs one info line for each fluid block that does not hold a whole number of layers on every axis:
/// the size the lattice fills (whole spacings, as SampleFluid fills it) and the size asked for.
/// Returns the number of such blocks.
int LogCutBlocks(const SceneSetup& scene);

/// Boundary particles on the tank faces (layers outward) and the obstacle surfaces (layers inward),
/// spaced as close to the rest spacing as fits each face exactly. w is left 0 (volumes come later).
/// `viscosity` (may be null) receives each particle's wall friction alpha (floor or walls).
int64_t SampleBoundary(const SceneSetup& scene, std::vector<Vec4>* out, std::vector<float>* viscosity = nullptr);

/// Akinci et al. (2012) give a boundary particle the volume V_b = 1 / sum_k W_bk over its boundary
/// neighbours. For a wall of `layers` sheets one spacing behind the fluid's first layer, the density a
/// fluid particle at rest then receives is a few per cent too high (6.4 % for one sheet, cubic spline,
/// support 2 dx), and WCSPH turns 1 % of density into twice the hydrostatic pressure of a 10 cm column.
/// This returns gamma such that Psi_b = gamma rho0 V_b gives exactly rho0 next to a flat wall in the
/// rest lattice (about 0.70 for one sheet); edges and corners then come out 0.6 % and 1.5 % light,
/// which the pressure clamp at zero tolerates, instead of 11 % and 15 % heavy.
float WallDensityCorrection(const CubicSpline& kernel, float dx, int layers);

/// The same for the pressure force: gamma_grad such that gamma_grad rho0 sum_b V_b gradW_0b equals the
/// gradient sum of the missing fluid half space, so that a uniform pressure pushes a particle next to a
/// flat wall neither into it nor away. Equal to WallDensityCorrection at support 2 dx (0.7006 both);
/// 4.7 % above it at 2.5 dx, where using the density factor let particles sink into the walls.
float WallGradientCorrection(const CubicSpline& kernel, float dx, int layers);

/// PBF's constraint-force mixing scale (solvers/pbf/pbf.h): sum_j |grad_j C_i|^2 = sum_j (V |grad W_ij|)^2
/// for a particle inside the rest lattice, in 1/m^2; the scene's pbf_relaxation is a fraction of it.
float PbfRestGradientSum(const CubicSpline& kernel, float dx, float volume);

/// sum_f W_bf for a boundary particle of the first sheet of a flat wall with the fluid's rest lattice
/// beside it (the fluid's first layer one spacing away): the reference of the walls' own density.
float WallFluidSum(const CubicSpline& kernel, float dx);

/// For each boundary particle, 1 / sum_f W_bf over the fluid's rest lattice filling the whole tank
/// (minus obstacles): the reference its own density is measured against (WallPressureStage). Edges
/// and corners see a quarter and an eighth of the fluid a flat wall sees, and get a reference to match.
/// The reference is floored at `floorFraction` of the flat wall's, so that a particle behind the first
/// sheet, which sees almost no fluid at rest, does not turn one stray neighbour into a huge pressure.
std::vector<float> WallInverseReferences(const SceneSetup& scene, const CubicSpline& kernel,
                                         const std::vector<Vec4>& boundary, float floorFraction);

/// Neighbour-list slots per fluid particle: 1.4 x the rest-lattice count (4/3) pi support_factor^3,
/// room for 40 % compression or clustering before a particle falls back to scanning its cells.
int NeighbourCapacity(float supportFactor);

/// The grid over the tank plus the boundary layers, cells of the kernel support.
GridShape MakeGridShape(const SceneSetup& scene);

}  // namespace sphxr::sim
