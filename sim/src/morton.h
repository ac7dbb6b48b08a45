#pragma once
// Morton (Z-order) codes of 3D cell coordinates, 10 bits per axis (Huang et al. 2013, §3.1: particles
// sorted by the Z-order of their cell, so that neighbouring cells lie close in memory).
#include <cstdint>

#include "sphxr/common/hd.h"

namespace sphxr::sim {

inline constexpr int kMortonBitsPerAxis = 10;
inline constexpr int kMaxGridDim = 1 << kMortonBitsPerAxis;

/// Spreads the low 10 bits of v so that there are two zero bits between each.
SPHXR_HD SPHXR_INLINE uint32_t MortonSpread(uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

SPHXR_HD SPHXR_INLINE uint32_t MortonCompact(uint32_t v) {
  v &= 0x09249249u;
  v = (v | (v >> 2)) & 0x030c30c3u;
  v = (v | (v >> 4)) & 0x0300f00fu;
  v = (v | (v >> 8)) & 0x030000ffu;
  v = (v | (v >> 16)) & 0x000003ffu;
  return v;
}

SPHXR_HD SPHXR_INLINE uint32_t MortonEncode(uint32_t x, uint32_t y, uint32_t z) {
  return MortonSpread(x) | (MortonSpread(y) << 1) | (MortonSpread(z) << 2);
}

SPHXR_HD SPHXR_INLINE void MortonDecode(uint32_t code, uint32_t* x, uint32_t* y, uint32_t* z) {
  *x = MortonCompact(code);
  *y = MortonCompact(code >> 1);
  *z = MortonCompact(code >> 2);
}

}  // namespace sphxr::sim
