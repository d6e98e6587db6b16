// afterglow's precompute and bake: the stages of stages.h from the ray tracer to the reflection
// passes, then one run of the runtime solver with the authored lights. The scene must already
// carry lightmap UVs (uv::unwrap); bakefiles/pipeline.h runs the whole job, UVs and files
// included.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/options.h"
#include "afterglow/core/stages.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

struct StageTime {
  Stage stage = Stage::Load;
  double seconds = 0.0;
  uint64_t rays = 0;  // traced in the stage, closest-hit and occlusion rays together
};

struct BakeResult {
  runtime::TransportData transport;
  TexelSet texels;          // the lightmap's texels
  // Two resolutions (the scene carries indirect UVs, uv/indirect.h): the indirect grid's texels,
  // which the clusters, links and the transport's texels are made of; else empty, and those are
  // made of `texels`.
  TexelSet indirectTexels;
  Clusters clusters;
  // Per texel E/π: light arriving directly (sources and sky) and bounced light; texels marked
  // invalid hold whatever the stages left (the lightmaps fill them from their neighbours). With
  // two resolutions the sky is solved with the bounced light, on the indirect grid, and comes
  // with it.
  std::vector<glm::vec3> texelDirect;
  std::vector<glm::vec3> texelIndirect;
  std::vector<std::vector<glm::vec3>> lightmaps;  // per atlas, width*height linear E/π, dilated
  // Two resolutions: per indirect atlas, the grid's sky and bounced light (E/π, dilated), what
  // an engine composing the lightmap itself reads at the indirect UVs; else empty.
  std::vector<std::vector<glm::vec3>> indirectLightmaps;
  // Directional lightmaps (BakeOptions::directional, runtime/directional.h): per atlas of the
  // transport's texels (the grid's with two resolutions, else the lightmap's), the bounced
  // light's gradient ∂(E/π)/∂n along world x, y and z, width*height each, filled and dilated as
  // that atlas's light; empty without.
  std::vector<std::array<std::vector<glm::vec3>, 3>> directionalLightmaps;
  // Mixed lights' shadowmask (shadowmask.h): per lightmap atlas, width*height RGBA visible
  // fractions, filled and dilated like the lightmaps; empty when no light is mixed. Per scene
  // light, its channel (-1: none).
  std::vector<std::vector<glm::vec4>> shadowmasks;
  std::vector<int> shadowmaskChannel;
  // Per light probe, its occlusion of the mixed lights by shadowmask channel (probeOcclusion);
  // empty without probes or mixed lights.
  std::vector<glm::vec4> probeOcclusion;
  // Per light probe (BakeOptions::probes), its radiance SH from the same solve.
  std::vector<runtime::ShL2> probeSh;
  // Per reflection probe, its prefiltered radiance (mips 0..6): [0] the sky, [i + 1]
  // transport.reflections.probes[i]; empty without reflection probes. dfg is the split sum's
  // table (runtime::dfgTable(kDfgSize)) they were shaded with.
  std::vector<runtime::CubemapChain> reflectionChains;
  std::vector<glm::vec2> dfg;
  std::vector<StageTime> stages;  // in the order they ran
  uint64_t raysTraced = 0;      // every ray of the bake
  uint64_t raysIntersected = 0; // of which closest-hit queries (gather rays, texel placement)
  uint64_t raysOccluded = 0;    // and any-hit queries (shadow and visibility rays)
  std::vector<std::string> warnings;
};

// Whether the scene's bounced light is solved on an indirect grid: some lightmapped instance
// has indirect UVs.
bool hasIndirectGrid(const scenes::Scene& scene);

Result<BakeResult> bake(const scenes::Scene& scene, const BakeOptions& options = {},
                        Progress& progress = nullProgress());

}  // namespace afterglow::baker
