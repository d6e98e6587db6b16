// Stages 3 and 4 of the precompute: form factors (texel -> cluster, cluster -> cluster, sky
// transfer) and unit direct light per source, written into runtime::TransportData.
#pragma once

#include <cstdint>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

class RayTracer;

struct LinkOptions {
  int texelRays = 64;          // cosine-distributed rays per texel
  int clusterRays = 256;       // cosine-distributed rays per cluster (spread over its texels)
  float minWeight = 1e-4f;     // links below this form factor are folded into the nearest kept one
  // A texel whose rays hit the back of single-sided geometry more often than this is inside a
  // wall: it is marked invalid and later filled from its neighbours.
  float maxBackfaceFraction = 0.1f;  // unitless
};

struct DirectOptions {
  int lightSamples = 16;     // shadow rays per texel per light with a size (soft shadows)
  int emissiveSamples = 64;  // samples per texel over all emissive triangles
};

// Texel and cluster links, sky SH transfer and validity (texels whose samples are mostly inside
// geometry become invalid in `texels`). Rays are seeded from (texel, sample) so results do not
// depend on the thread count.
Status computeLinks(const scenes::Scene& scene, const RayTracer& tracer, TexelSet& texels,
                    const Clusters& clusters, const LinkOptions& options,
                    runtime::TransportData& transport, Progress& progress = nullProgress());

// One runtime::Source per light (unit colour and intensity) and per emissive material (unit
// radiance, sampled explicitly as area lights), with texel and cluster transfer.
Status computeDirect(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                     const Clusters& clusters, const DirectOptions& options,
                     runtime::TransportData& transport, Progress& progress = nullProgress());

}  // namespace afterglow::baker
