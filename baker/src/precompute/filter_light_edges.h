// The bounced light's smoothing kept from crossing a change in what light a texel's rays reach
// (issue 16): after the links, a texel near other geometry (one that gathers alone) stops
// smoothing with an atlas neighbour when one of their gather points gathers a first bounce of
// some source (each light, the sky: far_targets.h, ClusterLight) more
// than LinkOptions::filterLightRatio times the other's.
//
// Why: the smoothing's edge test is geometric (one surface, normals alike, within half the
// harmonic ray distance, in sight). On Sponza-sun at 8 texels/m a wall texel 8 cm behind a
// drape gathers a tenth of what its neighbour 7 cm away gathers past the drape's edge: both
// pass that test, and the smoothing made the first 12x too bright, the worst texel of the
// level against the reference path tracer. Each gather point's first bounce of each source,
// per unit source, is geometry (which clusters its rays reach and how much of each source
// those clusters receive), so the cut does not change when light colours, intensities,
// albedos or the sky change: relight still equals rebake.
#pragma once

#include <cstdint>
#include <vector>

#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"

namespace afterglow::baker {

// ... unless the two first bounces differ by less than noiseSigmas standard deviations of their
// difference, as the points' own rays measure it (LinkOptions::filterNoiseSigmas): a dark
// texel whose few rays found a sunlit patch two times where its neighbours found it none is
// noise for the smoothing to even out, not a light edge to keep.
//
// Clears the marks of transport.texelNeighbours between texels whose gather points differ
// like that, and rebuilds the gather maps from them. `pointRays`: per gather point, the rays
// behind its row. Needs the links, far clusters, shared far fields, sky transfer and the
// sources' cluster transfer. maxRatio <= 1: nothing changes; noiseSigmas <= 0: no noise test.
void cutSmoothingAcrossLight(const TexelSet& texels, float maxRatio, float noiseSigmas,
                             const std::vector<uint32_t>& pointRays,
                             runtime::TransportData& transport);

}  // namespace afterglow::baker
