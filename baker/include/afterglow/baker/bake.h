// afterglow bake: the precompute followed by one run of the runtime solver with the authored
// lights. The scene must already carry lightmap UVs (uv::unwrap).
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/reference.h"
#include "afterglow/baker/reflection_capture.h"
#include "afterglow/baker/texels.h"
#include "afterglow/baker/transport_precompute.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_sh.h"
#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

struct BakeOptions {
  TexelOptions texels;
  ClusterOptions clusters;
  LinkOptions links;
  DirectOptions direct;
  runtime::SolveOptions solve;       // bounces (0 = to convergence within 0.1%)
  float indirectIntensity = 1.0f;    // Unity's meaning: scales all indirect light
  float albedoBoost = 1.0f;          // Unity's meaning: >= 1 pushes albedo toward white
  glm::vec3 skyColor{0.0f};          // constant sky radiance, linear RGB
  std::string skyImage;              // equirect HDR image (overrides skyColor when set)
  int dilation = 2;                  // texels: how far each chart is dilated into its padding
  // Light probes to bake (positions and their tetrahedra, probes::tetrahedralize); none when
  // empty.
  runtime::ProbeTetrahedra probes;
  ProbeOptions probeOptions;
  // Reflection probes: the scene's (extras.afterglow.reflectionProbe), captured and solved with
  // this many bounces.
  ReflectionOptions reflections;
  // Validation: compute every texel with the reference path tracer instead of the precompute
  // and solve (no clusters, links or transport come out).
  bool reference = false;
  ReferenceOptions referenceOptions;
};

// Quality presets (`afterglow bake --quality`): rays and samples per texel.
//   draft    32 gather rays, 8 shadow rays (64 in penumbrae), 3 smoothing passes: a quick look
//   default  64 gather rays, 16 shadow rays (128 in penumbrae), 2 smoothing passes
//   high     256 gather rays, 32 shadow rays (512 in penumbrae), 1 smoothing pass
enum class Quality { Draft, Default, High };
BakeOptions bakePreset(Quality quality);

struct StageTime {
  std::string name;
  double seconds = 0.0;
  uint64_t rays = 0;  // traced in the stage, closest-hit and occlusion rays together
};

struct BakeResult {
  runtime::TransportData transport;
  TexelSet texels;
  Clusters clusters;
  // Per texel E/π: light arriving directly (sources and sky) and bounced light; texels marked
  // invalid hold whatever the stages left (the lightmaps fill them from their neighbours).
  std::vector<glm::vec3> texelDirect;
  std::vector<glm::vec3> texelIndirect;
  std::vector<std::vector<glm::vec3>> lightmaps;  // per atlas, width*height linear E/π, dilated
  // Per light probe (BakeOptions::probes), its radiance SH from the same solve.
  std::vector<runtime::ShL2> probeSh;
  // Per reflection probe, its prefiltered radiance (mips 0..6): [0] the sky, [i + 1]
  // transport.reflections.probes[i]; empty without reflection probes. dfg is the split sum's
  // table (runtime::dfgTable(kDfgSize)) they were shaded with.
  std::vector<runtime::CubemapChain> reflectionChains;
  std::vector<glm::vec2> dfg;
  std::vector<StageTime> stages;
  uint64_t raysTraced = 0;      // every ray of the bake
  uint64_t raysIntersected = 0; // of which closest-hit queries (gather rays, texel placement)
  uint64_t raysOccluded = 0;    // and any-hit queries (shadow and visibility rays)
  std::vector<std::string> warnings;
};

Result<BakeResult> bake(const scenes::Scene& scene, const BakeOptions& options = {},
                        Progress& progress = nullProgress());

}  // namespace afterglow::baker
