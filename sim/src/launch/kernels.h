#pragma once
// What each thrust or CUB algorithm launches on CUDA (CCCL 3.0, CUDA 13), so that cpu-reference, which
// runs the CUDA backend's orchestration on thrust's OpenMP system, counts what the CUDA backend does.
// Read from the CCCL sources (docs/dev/backends.md, "What a step launches", has the table):
//   for_each_n, fill, gather, transform   one parallel_for kernel   (thrust/system/cuda/detail/parallel_for.h)
//   radix sort, 32-bit keys               single tile: 1 kernel; else the onesweep path: 2 memsets, the
//                                         histogram, the exclusive sum, then per 8-bit pass a memset and
//                                         the onesweep kernel: 12   (cub/device/dispatch/dispatch_radix_sort.cuh)
//   reduce, transform_reduce, count_if    single tile: 1 kernel; else the reduce and the single-tile pass: 2
//                                         (cub/device/dispatch/dispatch_reduce.cuh)
//   exclusive_scan                        the tile-state init and the scan: 2   (dispatch_scan.cuh)
//   copy_if                               the tile-state init and the select: 2   (dispatch_select_if.cuh)
// The single-tile sizes are the sm_80/sm_90 policies' (tuning_radix_sort.cuh: 256 threads x 19 keys;
// tuning_reduce.cuh: 256 threads x 16 items of 4 bytes).
#include <cstdint>

namespace sphxr::sim::kernels {

inline constexpr int kParallelFor = 1;
inline constexpr int kScan = 2;
inline constexpr int kSelect = 2;

inline constexpr int SortPairs(int64_t n) {
  if (n <= 1) return 0;                 // nothing to order: CUB returns before any launch
  if (n <= 256 * 19) return 1;          // DeviceRadixSortSingleTileKernel
  return 2 + 2 + 4 * 2;                 // memsets, histogram, exclusive sum; 4 passes of 8 bits
}

inline constexpr int Reduce(int64_t n) { return n <= 256 * 16 ? 1 : 2; }

}  // namespace sphxr::sim::kernels
