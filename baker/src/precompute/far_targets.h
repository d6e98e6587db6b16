// Far clusters as link targets (hierarchical links), shared by the gather points' links
// (links.cpp) and the light probes' (probe_transfer.cpp), so both pick the same far cluster for
// a hit seen from the same distance.
#pragma once

#include <cstdint>
#include <vector>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::baker {

// Far clusters as link targets: per level and texel, its far cluster (front sides only,
// numbered from 0 across the levels), per far cluster the squared distance beyond which a hit
// links it, and what such a hit links: the far cluster's row in transport.farClusters, or, for
// a far cluster of a single cluster (a small instance, most of them on Sponza), that cluster
// itself, which reflects the very same light without a far row to mix each bounce or a slot
// of R to read it from.
struct FarTargets {
  std::vector<std::vector<uint32_t>> ofTexel;  // [level][texel]
  std::vector<float> reach2;
  std::vector<uint32_t> target;  // a cluster, or clusterCount + its row of farClusters
  std::vector<uint8_t> unlike;   // 1: its clusters are lit unlike each other (ClusterLight)
  uint32_t rows = 0;             // far clusters that got a row (those of several clusters)

  // The link target of the coarsest far cluster of texel t that a point at squared distance
  // d2 sees from far enough and whose clusters are lit alike, or runtime::kNoTexel. `seenFar`
  // (optional) tells whether any far cluster of t is seen from far enough, lit alike or not.
  uint32_t of(uint32_t t, float d2, bool* seenFar = nullptr) const {
    if (seenFar) *seenFar = false;
    for (size_t level = ofTexel.size(); level-- > 0;) {
      const uint32_t f = ofTexel[level][t];
      if (f == runtime::kNoTexel || !(d2 > reach2[f])) continue;
      if (seenFar) *seenFar = true;
      if (!unlike[f]) return target[f];
    }
    return runtime::kNoTexel;
  }
  bool empty() const { return reach2.empty(); }
};

// How much light each source sends to each cluster directly, for the far clusters' light
// check: per channel (each light's unit direct light, of the first 32 sources, then the sky's
// constant term), per cluster, and per channel a floor below which differences do not count
// (a twentieth of its mean over clusters). Read from the transport's sources and clusterSky,
// so the links and the probes build the same. Emissive materials are left out: whether one is
// a source at all depends on its emission, which a relight may change (and a bake of the relit
// scene would then decide differently), while a light's unit transfer is geometry.
// maxRatio <= 1: empty (no check).
struct ClusterLight {
  std::vector<std::vector<float>> channels;  // [channel][cluster]
  std::vector<float> floors;                 // [channel]
  float maxRatio = 0.0f;
  bool empty() const { return channels.empty(); }
};
ClusterLight clusterLight(const runtime::TransportData& transport, float maxRatio);

// Numbers the front far clusters level by level, fills farClusters (each the area-weighted mix
// of the clusters its texels belong to, for those of several clusters) and the targets. A far
// cluster's radius is the farthest of its texels' corners from its centre. Deterministic: the
// probes rebuild the same targets, without the rows (farClusters null).
// With `light`, a texel whose cluster is not lit like its far cluster's mean (in some channel
// the larger exceeds maxRatio × the smaller plus the floor) does not link that far cluster but
// a finer one, or its own cluster: a hit seen through a gap in the shaded half of a half-sunlit
// far cluster must not take the sunlit half's light (issue 16).
FarTargets farTargets(const TexelSet& texels, const Clusters& clusters,
                      const std::vector<Clusters>& levels, float farDistance,
                      runtime::SparseMatrix* farClusters, const ClusterLight& light = {});

}  // namespace afterglow::baker
