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
  uint32_t rows = 0;             // far clusters that got a row (those of several clusters)

  // The link target of the coarsest far cluster of texel t that a point at squared distance
  // d2 sees from far enough, or runtime::kNoTexel.
  uint32_t of(uint32_t t, float d2) const {
    for (size_t level = ofTexel.size(); level-- > 0;) {
      const uint32_t f = ofTexel[level][t];
      if (f != runtime::kNoTexel && d2 > reach2[f]) return target[f];
    }
    return runtime::kNoTexel;
  }
  bool empty() const { return reach2.empty(); }
};

// Numbers the front far clusters level by level, fills farClusters (each the area-weighted mix
// of the clusters its texels belong to, for those of several clusters) and the targets. A far
// cluster's radius is the farthest of its texels' corners from its centre. Deterministic: the
// probes rebuild the same targets, without the rows (farClusters null).
FarTargets farTargets(const TexelSet& texels, const Clusters& clusters,
                      const std::vector<Clusters>& levels, float farDistance,
                      runtime::SparseMatrix* farClusters);

}  // namespace afterglow::baker
