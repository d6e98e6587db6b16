// Stage direct: unit direct light. One runtime::Source per light (unit colour and intensity)
// and per emissive material (unit radiance, sampled explicitly as area lights), with texel and
// cluster transfer and soft shadows (DirectOptions).
#pragma once

#include "afterglow/baker/clusters.h"
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

// The runtime's light mode of a scene light's.
inline runtime::LightMode lightMode(scenes::LightMode mode) {
  return mode == scenes::LightMode::Mixed      ? runtime::LightMode::Mixed
         : mode == scenes::LightMode::Realtime ? runtime::LightMode::Realtime
                                               : runtime::LightMode::Baked;
}

Status computeDirect(const scenes::Scene& scene, const trace::RayTracer& tracer,
                     const TexelSet& texels, const Clusters& clusters,
                     const DirectOptions& options, runtime::TransportData& transport,
                     Progress& progress = nullProgress());

// Two resolutions: when `texels` above were the indirect grid's, each source's direct light at
// the lightmap's own texels, into transport.lightmap's direct layers (the sources computeDirect
// made, in its order; the same shadow rays per texel as there, seeded by lightmap texel).
Status computeLightmapDirect(const scenes::Scene& scene, const trace::RayTracer& tracer,
                             const TexelSet& lightmapTexels, const DirectOptions& options,
                             runtime::TransportData& transport,
                             Progress& progress = nullProgress());

}  // namespace afterglow::baker
