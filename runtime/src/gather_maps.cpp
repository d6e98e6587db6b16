// The texels' and gather points' maps (TransportData::texelGather, pointFilter) from their
// source: each texel's gather point and which atlas neighbours it may smooth with. The baker
// builds them here and the loader rebuilds them here, so a loaded transport holds the very maps
// the bake solved with, while the file stores five bytes a texel instead of the maps' forty.
#include <algorithm>
#include <utility>
#include <vector>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

namespace {

// The tent over a texel's marked neighbours: 4 for itself, 2 along the axes, 1 on diagonals.
// (Small integers: a row's sums, SparseMatrix::appendNormalisedRow, are exact in any order.)
float tentWeight(int k) {
  return (kNeighbourOffsets[k][0] == 0 || kNeighbourOffsets[k][1] == 0) ? 2.0f : 1.0f;
}

}  // namespace

std::string checkGatherSource(const TransportData& d) {
  if (d.texelPoint.size() != d.texelCount || d.texelNeighbours.size() != d.texelCount)
    return "gather maps: " + std::to_string(d.texelPoint.size()) + " texel points and " +
           std::to_string(d.texelNeighbours.size()) + " neighbour masks for " +
           std::to_string(d.texelCount) + " texels";
  for (size_t t = 0; t < d.texelPoint.size(); ++t)
    if (d.texelPoint[t] != kNoTexel && d.texelPoint[t] >= d.gatherPointCount)
      return "gather maps: texel " + std::to_string(t) + " reads gather point " +
             std::to_string(d.texelPoint[t]) + " of " + std::to_string(d.gatherPointCount);
  if (d.filterPasses < 0) return "gather maps: negative filter passes";
  return {};
}

void buildGatherMaps(TransportData& d, const ParallelFor& parallelFor) {
  const uint32_t count = d.texelCount, points = d.gatherPointCount;
  // Where each texel sits: its atlas and pixel (texels are numbered in atlas scan order, one
  // pixel each; a texel no pixel names has no neighbours, and neither have the texels of an
  // atlas whose size does not match its pixels, which validate() refuses afterwards).
  std::vector<uint32_t> atlasOf(count, kNoTexel), pixelOf(count, 0);
  for (size_t a = 0; a < d.atlases.size(); ++a) {
    const AtlasLayout& layout = d.atlases[a];
    if (layout.width <= 0 || layout.height <= 0 ||
        layout.texelOfPixel.size() != size_t(layout.width) * size_t(layout.height))
      continue;
    const std::vector<uint32_t>& pixels = layout.texelOfPixel;
    for (size_t p = 0; p < pixels.size(); ++p) {
      const uint32_t t = pixels[p];
      if (t < count && atlasOf[t] == kNoTexel) {
        atlasOf[t] = uint32_t(a);
        pixelOf[t] = uint32_t(p);
      }
    }
  }
  const bool smooth = d.filterPasses > 0;
  // Texels per gather point: a point of one texel is a texel near other geometry.
  std::vector<uint32_t> pointSize(points, 0);
  for (uint32_t p : d.texelPoint)
    if (p < points) ++pointSize[p];
  // A texel's mix: its own point (4), and with smoothing its marked neighbours' (tent). A texel
  // near other geometry mixes a neighbour only when it also mixes the one opposite: its tent is
  // then symmetric and keeps a linear change of light as it is. At the edge of a surface
  // (a ceiling meeting a wall, the rim of a lamp), where bounced light falls off steeply, a
  // one-sided tent averaged the edge texel with brighter texels on one side only: 8-12% too
  // bright against the path tracer on the Cornell box's ceiling. Block texels keep their
  // one-sided neighbours: they gather a quarter of the rays, and at a chart's edge on an open
  // wall the light there is flat and the noise is what the smoothing is for.
  auto mixOf = [&](uint32_t t, std::vector<std::pair<uint32_t, float>>& out) {
    out.emplace_back(d.texelPoint[t], 4.0f);
    if (!smooth || atlasOf[t] == kNoTexel) return;
    const AtlasLayout& layout = d.atlases[atlasOf[t]];
    const int x = int(pixelOf[t] % uint32_t(layout.width)), y = int(pixelOf[t] / uint32_t(layout.width));
    const uint8_t marks = d.texelNeighbours[t];
    const bool paired = d.texelPoint[t] < points && pointSize[d.texelPoint[t]] == 1;
    for (int k = 0; k < 8; ++k) {
      // kNeighbourOffsets[7 - k] is the neighbour opposite kNeighbourOffsets[k].
      if (!(marks & (1u << k)) || (paired && !(marks & (1u << (7 - k))))) continue;
      const int nx = x + kNeighbourOffsets[k][0], ny = y + kNeighbourOffsets[k][1];
      if (nx < 0 || ny < 0 || nx >= layout.width || ny >= layout.height) continue;
      const uint32_t n = layout.texelOfPixel[size_t(ny) * size_t(layout.width) + size_t(nx)];
      if (n >= count || d.texelPoint[n] == kNoTexel) continue;
      out.emplace_back(d.texelPoint[n], tentWeight(k));
    }
  };
  using Entries = std::vector<std::pair<uint32_t, float>>;
  d.texelGather = normalisedRows(count, [&](size_t t, Entries& entries) {
    if (d.texelPoint[t] != kNoTexel) mixOf(uint32_t(t), entries);
  }, parallelFor);
  // A point takes the mean over its texels of that same mix (the tent applied to the points'
  // values as the texels see them, averaged back over the point).
  d.pointFilter = SparseMatrix();
  if (!smooth) return;
  std::vector<uint32_t> start(size_t(points) + 1, 0), members;
  for (uint32_t p = 0; p < points; ++p) start[p + 1] = start[p] + pointSize[p];
  members.resize(start[points]);
  std::vector<uint32_t> next(start.begin(), start.end() - 1);
  for (uint32_t t = 0; t < count; ++t)
    if (d.texelPoint[t] != kNoTexel) members[next[d.texelPoint[t]]++] = t;
  d.pointFilter = normalisedRows(points, [&](size_t p, Entries& entries) {
    for (uint32_t k = start[p]; k < start[p + 1]; ++k) {
      const size_t before = entries.size();
      mixOf(members[k], entries);
      // Neighbours inside the point are the point itself: only the centre weight counts for
      // it, so a block smooths with its neighbours as strongly as a texel does with its own.
      for (size_t i = before + 1; i < entries.size(); ++i)
        if (entries[i].first == p) entries[i].second = 0.0f;
    }
  }, parallelFor);
}

}  // namespace afterglow::runtime
