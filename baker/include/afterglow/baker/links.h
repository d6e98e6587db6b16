// Stage links: the form factors. The links of the gather points and of the back-side clusters
// (which cast rays of their own), how clusters and texels read the gather points, the smoothing
// between gather points, sky transfer, the materials and per-cluster texture modulation, all
// written into runtime::TransportData.
#pragma once

#include <vector>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/gather.h"
#include "afterglow/baker/options.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::trace {
class RayTracer;
}  // namespace afterglow::trace

namespace afterglow::baker {

// With far cluster levels (coarser clusterings of the same texels, finest first; their back
// sides are not used), a gather point's hit links the coarsest far cluster it lies farther
// from than LinkOptions::farDistance × that cluster's radius
// (runtime::TransportData::farClusters), else the hit texel's cluster.
Status computeLinks(const scenes::Scene& scene, const trace::RayTracer& tracer,
                    const TexelSet& texels, const TexelGather& gather, const Clusters& clusters,
                    const LinkOptions& options, runtime::TransportData& transport,
                    Progress& progress = nullProgress(),
                    const std::vector<Clusters>& farLevels = {});

}  // namespace afterglow::baker
