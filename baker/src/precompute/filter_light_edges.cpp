#include "precompute/filter_light_edges.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "afterglow/core/parallel.h"
#include "precompute/far_targets.h"

namespace afterglow::baker {

namespace {

using runtime::kNoTexel;
using runtime::SparseLinks;
using runtime::TransportData;

// Row r of `links` applied to `values` (padding entries are code 0: weight 0).
double rowSum(const SparseLinks& links, size_t r, const std::vector<float>& values) {
  double sum = 0.0;
  for (size_t k = links.rowStart[r]; k < links.rowStart[r + 1]; ++k)
    sum += double(links.weightAt(r, k)) * double(values[links.targetAt(k)]);
  return sum;
}

// rowSum, and the same of the values' squares, in one walk of the row.
std::pair<double, double> rowSums(const SparseLinks& links, size_t r,
                                  const std::vector<float>& values) {
  double sum = 0.0, squares = 0.0;
  for (size_t k = links.rowStart[r]; k < links.rowStart[r + 1]; ++k) {
    const double w = double(links.weightAt(r, k)), v = double(values[links.targetAt(k)]);
    sum += w * v;
    squares += w * v * v;
  }
  return {sum, squares};
}

// Every gather point's first bounce of one source, per unit source and unit albedo: the
// clusters' received light `received` (per cluster) carried through the far clusters, the
// shared far fields and the links, as the solver's first pass carries reflected light.
// With `rays` (per gather point, the rays behind its row), also the variance of that estimate
// in `variance`: the spread of what single rays bring (the row's weights are the rays' shares;
// the misses bring nothing) over the rays. A far cluster or a shared far field counts as one
// value, so the spread of far light is understated: where in doubt, the edge stays.
std::vector<float> firstBounce(const TransportData& d, std::vector<float> received,
                               const std::vector<uint32_t>& rays, std::vector<float>& variance) {
  const size_t clusters = d.clusterCount, far = d.farClusters.rows();
  received.resize(d.linkTargetCount(), 0.0f);
  parallelFor(far, [&](size_t f) {
    double sum = 0.0;
    for (uint32_t k = d.farClusters.rowStart[f]; k < d.farClusters.rowStart[f + 1]; ++k)
      sum += double(d.farClusters.weight[k]) * double(received[d.farClusters.column[k]]);
    received[clusters + f] = float(sum);
  }, 4096);
  const size_t base = d.sharedFarBase();
  parallelFor(d.sharedFar.rows(), [&](size_t s) {
    received[base + s] = float(rowSum(d.sharedFar, s, received));
  }, 1024);
  std::vector<float> gathered(d.gatherPointCount, 0.0f);
  const bool withVariance = rays.size() == d.gatherPointCount;
  variance.assign(withVariance ? d.gatherPointCount : 0, 0.0f);
  parallelFor(d.gatherPointCount, [&](size_t p) {
    if (!withVariance) {
      gathered[p] = float(rowSum(d.links, p, received));
      return;
    }
    const auto [mean, squares] = rowSums(d.links, p, received);
    gathered[p] = float(mean);
    if (rays[p] > 1)
      variance[p] = float(std::max(0.0, squares - mean * mean) / double(rays[p] - 1));
  }, 1024);
  return gathered;
}

}  // namespace

void cutSmoothingAcrossLight(const TexelSet& texels, float maxRatio, float noiseSigmas,
                             const std::vector<uint32_t>& pointRays, TransportData& d) {
  if (!(maxRatio > 1.0f) || d.texelNeighbours.size() != texels.size()) return;
  const ClusterLight light = clusterLight(d, maxRatio);
  const size_t count = texels.size();
  // Only texels that gather alone (near other geometry) are checked: there light changes
  // within a texel or two and their many rays make the first bounce precise. Between two
  // points of 2×2 blocks the check measurably makes things worse: their first bounces differ
  // by noise, which is what the smoothing is for.
  std::vector<uint32_t> texelsOfPoint(d.gatherPointCount, 0);
  for (uint32_t p : d.texelPoint)
    if (p != kNoTexel) ++texelsOfPoint[p];
  auto alone = [&](size_t t) { return texelsOfPoint[d.texelPoint[t]] == 1; };
  std::vector<uint8_t> cut(count, 0);
  for (const std::vector<float>& received : light.channels) {
    std::vector<float> var;
    const std::vector<float> v =
        firstBounce(d, received, noiseSigmas > 0.0f ? pointRays : std::vector<uint32_t>(), var);
    // Differences below a fifth of the mean first bounce do not count: dim texels' own noise.
    double mean = 0.0;
    for (float x : v) mean += double(x);
    const float floor = float(0.2 * mean / double(std::max<size_t>(v.size(), 1)));
    parallelFor(count, [&](size_t t) {
      const uint8_t marks = d.texelNeighbours[t];
      if (!marks || d.texelPoint[t] == kNoTexel) return;
      const runtime::AtlasLayout& layout = texels.atlases[texels.atlas[t]];
      const float own = v[d.texelPoint[t]];
      for (int k = 0; k < 8; ++k) {
        if (!(marks & (1u << k))) continue;
        const int x = texels.pixel[t].x + runtime::kNeighbourOffsets[k][0];
        const int y = texels.pixel[t].y + runtime::kNeighbourOffsets[k][1];
        const uint32_t n = layout.texelOfPixel[size_t(y) * size_t(layout.width) + size_t(x)];
        if (n == kNoTexel || d.texelPoint[n] == kNoTexel || (!alone(t) && !alone(n))) continue;
        const float other = v[d.texelPoint[n]];
        if (!(std::max(own, other) > maxRatio * std::min(own, other) + floor)) continue;
        // A difference their rays cannot tell from noise is no edge: the smoothing is what
        // evens it out.
        if (!var.empty() &&
            double(std::abs(own - other)) <
                double(noiseSigmas) *
                    std::sqrt(double(var[d.texelPoint[t]]) + double(var[d.texelPoint[n]])))
          continue;
        cut[t] |= uint8_t(1u << k);
      }
    }, 4096);
  }
  // The test is symmetric, so the marks stay symmetric.
  for (size_t t = 0; t < count; ++t) d.texelNeighbours[t] &= uint8_t(~cut[t]);
  runtime::buildGatherMaps(d, blockRanges());
}

}  // namespace afterglow::baker
