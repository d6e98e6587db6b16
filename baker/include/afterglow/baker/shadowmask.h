// Unity's shadowmask for mixed lights (extras.afterglow.mode "mixed"): the engine draws a
// mixed light's direct light itself, and reads the light's static shadow from one channel of
// an RGBA texture at the lightmap's UVs. Each mixed light gets a channel that no mixed light
// overlapping it has (a directional light overlaps every light; a point or spot light reaches
// its range, everywhere without one), first come first served in the scene's light order, as
// Unity assigns them; a mixed light that finds all four taken gets none and is reported.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/texels.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

constexpr int kShadowmaskChannels = 4;

// Per scene light, its shadowmask channel (0..3), or -1: not mixed, or no channel free (those
// lights' names are appended to *overflow).
std::vector<int> shadowmaskChannels(const std::vector<scenes::Light>& lights,
                                    std::vector<std::string>* overflow = nullptr);

// Per lightmap texel, channel c = the visible fraction of the light given channel c (its unit
// direct light over the same light unshadowed, 0..1), 1 where no light has the channel or the
// texel faces away from it. Read from the transport's unit direct light per lightmap texel
// (the sources' texel transfer, or with two resolutions the lightmap layers), so the
// shadowmask has the penumbrae the direct light has.
std::vector<glm::vec4> shadowmaskTexels(const scenes::Scene& scene, const TexelSet& lightmap,
                                        const runtime::TransportData& transport,
                                        const std::vector<int>& channels);

// Light probes' occlusion for mixed lights (Unity's probe occlusion): per probe position,
// channel c = the visible fraction of the light given channel c, from `rays` stratified shadow
// rays over its extent (one without an extent), 1 where no light has the channel. An engine
// multiplies a mixed light's direct light on a dynamic object by it, mixed like the probes' SH.
std::vector<glm::vec4> probeOcclusion(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                      const std::vector<glm::vec3>& positions,
                                      const std::vector<int>& channels, int rays = 64);

}  // namespace afterglow::baker
