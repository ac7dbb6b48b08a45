#pragma once
// The CPU backend's SIMD traversals of the density and force stages (host-only; the CUDA backend runs
// stages.h's DensityStage and ForceStage, a thread per particle). The physics is stages.h's: these
// only arrange the same sums for vector units (kLanes wide: 8 with AVX, else 16; see kLanes).
//
// Density (DensityBlockStage): one work item per block of up to kLanes particles of one box of grid cells
// (particles are sorted by Morton code, so a Morton-aligned box is a contiguous run: a pair of cells along
// x where the water is dense, up to 4 x 4 x 4 cells in spray; BlockBoxOf). Each candidate j of the cells around
// the block is loaded once and evaluated for all the block's particles at once: the distance, the hit
// mask, sqrt and the kernel (both pieces, selected per lane); the neighbour-list appends are scalar
// (kVectorAppends: on AVX and AVX-512 without a branch per hit). The per-particle DensityStage does the same one
// candidate and one particle at a time, with a branch per candidate and per kernel piece. Same cells, same candidate order: each
// particle's sum adds the same terms in the same order and its neighbour list is the same list; a
// kernel value may differ in the last bit where the compiler fuses a multiply-add differently.
//
// Forces (ForceListStage): per particle, its neighbour list kLanes at a time, the neighbours' fields
// loaded into vectors (GatherXyz, Gather), the pair terms of ForceStage in every lane, the lanes summed at the end. The
// sum's order differs from ForceStage's serial one (rounding only). The wall terms are summed the same
// way, kLanes wall particles at a time from the particle's cells; the bodies, gravity and the reuse
// guard are ForceStage::Store itself.
//
// Walls: the density blocks take the walls' kernel sums like the fluid's (each lane's terms in its own
// scan's order), and WallPressureBlockStage the wall particles of one cell kLanes at a time.
//
// All are deterministic for any thread count (a particle's sums never depend on the schedule), and
// the CPU runs them for every density and force evaluation, with reuse too (DensityBlockStage's
// blocks then drawn from the particles that compute, BlockSet; masked lanes only for the pairs-only
// layout), so reuse off and reuse with IDLE = 0 stay bit-identical. tests/sim/cpu_stages_test.cpp compares each with the per-particle stages and with
// brute force.
//
// The solvers' own SIMD forms live in their folders (solvers/pbf/pbf_simd.h, solvers/dfsph/dfsph_simd.h):
// their neighbour passes as the forces', per particle over the list kLanes at a time, each pair's kernel
// gradient kept lane-blocked for the passes after it; the launcher (cpu/launcher.h) includes them.
//
// One header per stage, beside the stage it implements (stages/):
#include "../stages.h"    // the stages these implement (sim/src/stages.h, not this file)
#include "cpu/simd.h"     // Lanes, kLanes, the tier's intrinsics
#include "cpu/blocks.h"   // the density blocks' layout and kernel sums
#include "cpu/density.h"  // DensityBlockStage
#include "cpu/forces.h"   // ForceListStage
#include "cpu/walls.h"    // WallPressureBlockStage
