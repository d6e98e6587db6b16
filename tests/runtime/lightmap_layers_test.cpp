// The lightmap layers' arithmetic (lightmap_layers.h): a lightmap texel's bilinear weights over
// the indirect texels around it, masked and renormalised, and the direct layers' half floats.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/runtime/lightmap_layers.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {
namespace {

// A 3 × 2 indirect atlas whose pixels are texels 0..5, row by row, but for pixel (2, 1).
std::vector<AtlasLayout> smallGrid() {
  AtlasLayout a;
  a.width = 3;
  a.height = 2;
  a.texelOfPixel = {0, 1, 2, 3, 4, kNoTexel};
  return {a};
}

IndirectCorners corners(int x, int y, int fx, int fy, int mask) {
  IndirectCorners c;
  c.x = uint16_t(x);
  c.y = uint16_t(y);
  c.fraction = uint8_t(fx | (fy << 4));
  c.mask = uint8_t(mask);
  return c;
}

TEST(LightmapLayers, CornerWeightsAreBilinearOverTheCountedTexels) {
  const std::vector<AtlasLayout> grid = smallGrid();
  uint32_t texel[4];
  float weight[4];
  // A quarter across, half up: (1 − ¼)(1 − ½), ¼(1 − ½), (1 − ¼)½, ¼·½.
  cornerWeights(corners(0, 0, 4, 8, 0xf), grid, texel, weight);
  const uint32_t want[4] = {0, 1, 3, 4};
  const float bilinear[4] = {0.375f, 0.125f, 0.375f, 0.125f};
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(texel[k], want[k]);
    EXPECT_FLOAT_EQ(weight[k], bilinear[k]);
  }
  // Corner 1 masked out (buried, or behind a wall): the others renormalised, 0.375 / 0.875 ...
  cornerWeights(corners(0, 0, 4, 8, 0xd), grid, texel, weight);
  EXPECT_FLOAT_EQ(weight[1], 0.0f);
  EXPECT_FLOAT_EQ(weight[0] + weight[2] + weight[3], 1.0f);
  EXPECT_FLOAT_EQ(weight[0], 0.375f / 0.875f);
  // A pixel without a texel counts as masked: square (1, 0)'s corner (2, 1).
  cornerWeights(corners(1, 0, 8, 8, 0xf), grid, texel, weight);
  EXPECT_EQ(texel[3], kNoTexel);
  EXPECT_FLOAT_EQ(weight[3], 0.0f);
  EXPECT_FLOAT_EQ(weight[0], 1.0f / 3.0f);
}

TEST(LightmapLayers, CornersWithoutBilinearWeightShareItEqually) {
  const std::vector<AtlasLayout> grid = smallGrid();
  uint32_t texel[4];
  float weight[4];
  // The point on the square's left edge, but only its right corners count (the left ones are
  // buried under an object the texel stands beside): they share it.
  cornerWeights(corners(0, 0, 0, 8, 0xa), grid, texel, weight);
  EXPECT_FLOAT_EQ(weight[1], 0.5f);
  EXPECT_FLOAT_EQ(weight[3], 0.5f);
  EXPECT_FLOAT_EQ(weight[0] + weight[2], 0.0f);
  // No corner counts: no light.
  cornerWeights(corners(0, 0, 4, 4, 0), grid, texel, weight);
  for (float w : weight) EXPECT_EQ(w, 0.0f);
}

TEST(LightmapLayers, DirectLayersKeepElevenSignificantBits) {
  // From a lamp 1 mm off a wall (E/π in the hundreds of thousands per candela) to a faint
  // corner: halves of value / largest keep each within 2^-11 of the largest (subnormal halves
  // below 2^-14 of it), and the largest exactly.
  const std::vector<float> values = {0.0f, 1e-7f, 0.37f, 12.5f, 3.1e5f, 2.0e3f};
  std::vector<uint16_t> halves;
  const float scale = encodeDirectLayer(values, halves);
  ASSERT_EQ(halves.size(), values.size());
  EXPECT_FLOAT_EQ(scale, 3.1e5f);
  for (size_t i = 0; i < values.size(); ++i) {
    const float back = halfToFloat(halves[i]) * scale;
    EXPECT_LE(std::abs(back - values[i]), std::max(std::abs(values[i]) / 2048.0f, scale * 6e-8f))
        << values[i];
  }
  EXPECT_EQ(halfToFloat(halves[4]) * scale, 3.1e5f);
  // All black: scale 1, zeros.
  EXPECT_EQ(encodeDirectLayer(std::vector<float>(3, 0.0f), halves), 1.0f);
  for (uint16_t h : halves) EXPECT_EQ(h, 0u);
}

}  // namespace
}  // namespace afterglow::runtime
