// Stage probes: the light probes' transfer (runtime::ProbeTransport; each source's
// probeTransfer), after computeLinks and computeDirect have filled the transport.
#pragma once

#include <vector>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/options.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::trace {
class RayTracer;
}  // namespace afterglow::trace

namespace afterglow::baker {

// For the probes of `mesh`: per probe, rays over the sphere give the sky's transfer, the
// emissive surfaces seen and, region by region, the links to the clusters (or the far clusters
// of `farLevels`, as computeLinks picks them with `farDistance` and `farLightRatio`) whose
// reflected light arrives; shadow rays give each light's. Seeded from (probe, ray):
// deterministic for any thread count.
Status computeProbeTransfer(const scenes::Scene& scene, const trace::RayTracer& tracer,
                            const TexelSet& texels, const Clusters& clusters,
                            const std::vector<Clusters>& farLevels, float farDistance,
                            float farLightRatio, const runtime::ProbeTetrahedra& mesh,
                            const ProbeOptions& options, runtime::TransportData& transport,
                            Progress& progress = nullProgress());

}  // namespace afterglow::baker
