// sampling::TiledSobol, the gather rays' points: each texel's, each 2×2 block's and each 4×4
// square's points are a (0, k, 2)-net (one point in every elementary interval of their count's
// area), and over many tiles every point is uniform (the scramble leaves no offset behind).
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "shading/sampling.h"

namespace afterglow::baker {
namespace {

// Whether `points` (a power of two of them, 2^k) put exactly one point in every elementary
// interval of area 2^-k: every split into 2^a × 2^(k-a) cells, a = 0 .. k.
bool isNet(const std::vector<glm::vec2>& points) {
  uint32_t k = 0;
  while ((1u << k) < points.size()) ++k;
  if ((1u << k) != points.size()) return false;
  for (uint32_t a = 0; a <= k; ++a) {
    const uint32_t across = 1u << a, down = 1u << (k - a);
    std::vector<int> seen(size_t(across) * down, 0);
    for (const glm::vec2& p : points) {
      const uint32_t x = uint32_t(p.x * float(across)), y = uint32_t(p.y * float(down));
      if (x >= across || y >= down || seen[size_t(y) * across + x]++) return false;
    }
  }
  return true;
}

// The points of the texels at pixels (x0 .. x0+size-1, y0 .. y0+size-1), n each.
std::vector<glm::vec2> square(uint64_t seed, uint32_t x0, uint32_t y0, uint32_t size,
                              uint32_t n) {
  std::vector<glm::vec2> out;
  for (uint32_t y = y0; y < y0 + size; ++y)
    for (uint32_t x = x0; x < x0 + size; ++x) {
      const sampling::TiledSobol points(seed, x, y, n);
      for (uint32_t s = 0; s < n; ++s) out.push_back(points.point(s));
    }
  return out;
}

TEST(TiledSobol, EachTexelBlockAndSquareIsAStratifiedNet) {
  for (uint64_t seed : {1ull, 77ull, 123456789ull}) {
    SCOPED_TRACE(seed);
    // A texel's 32 rays (a block member's share of 128), anywhere in a tile and across tiles.
    for (uint32_t x : {0u, 5u, 15u, 16u, 37u})
      EXPECT_TRUE(isNet(square(seed, x, 3, 1, 32)));
    // An aligned 2×2 block (128 rays: its gather point's set) and 4×4 square (512).
    EXPECT_TRUE(isNet(square(seed, 2, 6, 2, 32)));
    EXPECT_TRUE(isNet(square(seed, 20, 36, 2, 32)));
    EXPECT_TRUE(isNet(square(seed, 4, 8, 4, 32)));
    EXPECT_TRUE(isNet(square(seed, 0, 0, 16, 8)));  // a whole tile
    // A block that straddles two blocks is not aligned in the Morton order: no net promised,
    // and in general none (the test above could pass by accident only if it were).
    EXPECT_FALSE(isNet(square(seed, 1, 0, 2, 32)));
  }
}

TEST(TiledSobol, EveryPointIsUniformOverTiles) {
  // Texel (3, 5)'s first point over 4096 tiles (different seeds): the mean of x, y and x·y must
  // be those of a uniform point (1/2, 1/2, 1/4) within a few standard errors, and each quarter
  // of the square must hold a quarter of them. A fixed offset left by the scramble fails this.
  const int tiles = 4096;
  double sx = 0, sy = 0, sxy = 0;
  int quarter[4] = {0, 0, 0, 0};
  for (int i = 0; i < tiles; ++i) {
    const glm::vec2 p = sampling::TiledSobol(sampling::mix64(uint64_t(i)), 3, 5, 32).point(7);
    sx += p.x, sy += p.y, sxy += double(p.x) * double(p.y);
    ++quarter[(p.x < 0.5f ? 0 : 1) + (p.y < 0.5f ? 0 : 2)];
  }
  const double se = 0.29 / std::sqrt(double(tiles));  // standard error of a uniform mean
  EXPECT_NEAR(sx / tiles, 0.5, 4 * se);
  EXPECT_NEAR(sy / tiles, 0.5, 4 * se);
  EXPECT_NEAR(sxy / tiles, 0.25, 4 * se);
  for (int q = 0; q < 4; ++q) EXPECT_NEAR(quarter[q], tiles / 4, 4 * std::sqrt(tiles * 0.1875));
}

}  // namespace
}  // namespace afterglow::baker
