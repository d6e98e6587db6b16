// buildGatherMaps' smoothing at the edges of a surface: a texel near other geometry (a gather
// point of its own) mixes a neighbour only with the one opposite, so light that changes
// linearly across the surface passes the smoothing unchanged, edges and corners included.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {
namespace {

// A width × height surface whose texels are marked to smooth with every neighbour on it; each
// texel its own gather point (`blocks` false) or one per 2×2 block.
TransportData surface(int width, int height, bool blocks) {
  TransportData d;
  d.texelCount = uint32_t(width * height);
  AtlasLayout layout;
  layout.width = width, layout.height = height;
  for (uint32_t t = 0; t < d.texelCount; ++t) layout.texelOfPixel.push_back(t);
  d.atlases.push_back(layout);
  const int blocksAcross = (width + 1) / 2;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      d.texelPoint.push_back(blocks ? uint32_t((y / 2) * blocksAcross + x / 2)
                                    : uint32_t(y * width + x));
      uint8_t marks = 0;
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kNeighbourOffsets[k][0], ny = y + kNeighbourOffsets[k][1];
        if (nx >= 0 && ny >= 0 && nx < width && ny < height) marks |= uint8_t(1u << k);
      }
      d.texelNeighbours.push_back(marks);
    }
  d.gatherPointCount = blocks ? uint32_t(blocksAcross * ((height + 1) / 2)) : d.texelCount;
  d.filterPasses = 2;
  buildGatherMaps(d);
  return d;
}

std::vector<double> applyRows(const SparseMatrix& m, const std::vector<double>& v) {
  std::vector<double> out(m.rows(), 0.0);
  for (size_t r = 0; r < m.rows(); ++r)
    for (uint32_t k = m.rowStart[r]; k < m.rowStart[r + 1]; ++k)
      out[r] += double(m.weight[k]) * v[m.column[k]];
  return out;
}

TEST(GatherMaps, TexelsNearGeometryKeepALinearChangeOfLightAtTheSurfacesEdge) {
  const int width = 7, height = 5;
  const TransportData d = surface(width, height, false);
  std::vector<double> ramp(d.gatherPointCount);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) ramp[size_t(y * width + x)] = 1.0 + 0.5 * x + 0.25 * y;
  // The point filter (twice, as the solver applies it) and the texels' reads both keep it.
  const std::vector<double> filtered = applyRows(d.pointFilter, applyRows(d.pointFilter, ramp));
  const std::vector<double> texels = applyRows(d.texelGather, filtered);
  for (size_t t = 0; t < texels.size(); ++t) {
    EXPECT_NEAR(filtered[t], ramp[t], 1e-5) << "point " << t;
    EXPECT_NEAR(texels[t], ramp[t], 1e-5) << "texel " << t;
  }
  // Inside, a texel still smooths with all eight neighbours; a corner with none.
  const uint32_t inside = 2 * width + 3, corner = 0;
  EXPECT_EQ(d.texelGather.rowStart[inside + 1] - d.texelGather.rowStart[inside], 9u);
  EXPECT_EQ(d.texelGather.rowStart[corner + 1] - d.texelGather.rowStart[corner], 1u);
}

}  // namespace
}  // namespace afterglow::runtime
