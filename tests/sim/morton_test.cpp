// Morton (Z-order) codes of cell coordinates (sim/src/morton.h), against a bit-by-bit interleave.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "morton.h"

namespace sphxr::sim {
namespace {

// Reference: bit b of x goes to bit 3b, of y to 3b+1, of z to 3b+2.
uint32_t NaiveInterleave(uint32_t x, uint32_t y, uint32_t z) {
  uint32_t code = 0;
  for (int b = 0; b < kMortonBitsPerAxis; ++b) {
    code |= ((x >> b) & 1u) << (3 * b);
    code |= ((y >> b) & 1u) << (3 * b + 1);
    code |= ((z >> b) & 1u) << (3 * b + 2);
  }
  return code;
}

void ExpectRoundTrip(uint32_t x, uint32_t y, uint32_t z) {
  const uint32_t code = MortonEncode(x, y, z);
  EXPECT_EQ(code, NaiveInterleave(x, y, z)) << "(" << x << ", " << y << ", " << z << ")";
  EXPECT_LT(code, 1u << (3 * kMortonBitsPerAxis)) << "30-bit code expected";
  uint32_t dx = ~0u, dy = ~0u, dz = ~0u;
  MortonDecode(code, &dx, &dy, &dz);
  EXPECT_EQ(dx, x) << "decode x of code " << code;
  EXPECT_EQ(dy, y) << "decode y of code " << code;
  EXPECT_EQ(dz, z) << "decode z of code " << code;
}

TEST(MortonTest, RoundTripEdgeCoordinates) {
  const uint32_t max = kMaxGridDim - 1;
  ASSERT_EQ(max, 1023u);
  const uint32_t edges[] = {0, 1, 2, 511, 512, 1022, max};
  for (uint32_t x : edges)
    for (uint32_t y : edges)
      for (uint32_t z : edges) ExpectRoundTrip(x, y, z);
  EXPECT_EQ(MortonEncode(0, 0, 0), 0u);
  EXPECT_EQ(MortonEncode(max, max, max), (1u << 30) - 1u);
}

TEST(MortonTest, RoundTripEveryValueOnEachAxis) {
  for (uint32_t v = 0; v < static_cast<uint32_t>(kMaxGridDim); ++v) {
    ExpectRoundTrip(v, 0, 0);
    ExpectRoundTrip(0, v, 0);
    ExpectRoundTrip(0, 0, v);
    ExpectRoundTrip(v, 1023 - v, v ^ 0x2aa);
  }
}

TEST(MortonTest, RoundTripRandom) {
  std::mt19937 rng(42);
  std::uniform_int_distribution<uint32_t> u(0, kMaxGridDim - 1);
  for (int i = 0; i < 100000; ++i) ExpectRoundTrip(u(rng), u(rng), u(rng));
}

TEST(MortonTest, DecodeOfEveryCodeIsInverse) {
  // Every 30-bit code in a strided sample decodes to coordinates that encode back to it.
  for (uint32_t code = 0; code < (1u << 30); code += 9973) {
    uint32_t x, y, z;
    MortonDecode(code, &x, &y, &z);
    ASSERT_LT(x, 1024u);
    ASSERT_LT(y, 1024u);
    ASSERT_LT(z, 1024u);
    ASSERT_EQ(MortonEncode(x, y, z), code);
  }
}

TEST(MortonTest, ChildrenOfAlignedBlockAreConsecutive) {
  // The 8 cells of a 2x2x2 block at even coordinates have codes base .. base + 7 with base a multiple of 8;
  // and more generally a 2^k block aligned at multiples of 2^k covers 8^k consecutive codes.
  std::mt19937 rng(1);
  std::uniform_int_distribution<uint32_t> u(0, kMaxGridDim / 2 - 1);
  for (int trial = 0; trial < 20000; ++trial) {
    const uint32_t x = 2 * u(rng), y = 2 * u(rng), z = 2 * u(rng);
    const uint32_t base = MortonEncode(x, y, z);
    EXPECT_EQ(base % 8u, 0u);
    std::vector<uint32_t> codes;
    for (uint32_t c = 0; c < 8; ++c) codes.push_back(MortonEncode(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2)));
    std::sort(codes.begin(), codes.end());
    for (uint32_t c = 0; c < 8; ++c) EXPECT_EQ(codes[c], base + c) << "block at (" << x << ", " << y << ", " << z << ")";
  }
  for (uint32_t k = 1; k <= 3; ++k) {
    const uint32_t side = 1u << k;
    const uint32_t x0 = 5 * side, y0 = 3 * side, z0 = 7 * side;
    std::set<uint32_t> codes;
    for (uint32_t i = 0; i < side; ++i)
      for (uint32_t j = 0; j < side; ++j)
        for (uint32_t l = 0; l < side; ++l) codes.insert(MortonEncode(x0 + i, y0 + j, z0 + l));
    ASSERT_EQ(codes.size(), side * side * side);
    EXPECT_EQ(*codes.rbegin() - *codes.begin() + 1, side * side * side) << "block of side " << side;
  }
}

TEST(MortonTest, MonotoneAlongEachAxis) {
  std::mt19937 rng(9);
  std::uniform_int_distribution<uint32_t> u(0, kMaxGridDim - 2);
  for (int trial = 0; trial < 20000; ++trial) {
    const uint32_t x = u(rng), y = u(rng), z = u(rng);
    const uint32_t c = MortonEncode(x, y, z);
    EXPECT_GT(MortonEncode(x + 1, y, z), c);
    EXPECT_GT(MortonEncode(x, y + 1, z), c);
    EXPECT_GT(MortonEncode(x, y, z + 1), c);
  }
}

}  // namespace
}  // namespace sphxr::sim
