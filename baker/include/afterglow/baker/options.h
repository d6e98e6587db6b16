// Every setting of the precompute, stage by stage, with its unit. The quality presets
// (bakePreset) and `afterglow bake`'s options set them; docs/tuning.md tells what each default
// was measured against.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include <glm/glm.hpp>

#include "afterglow/runtime/probe_tetrahedra.h"
#include "afterglow/runtime/solver.h"

namespace afterglow::baker {

// Stage texels (texels.h): one sample per covered lightmap texel.
struct TexelOptions {
  // Tangent rays around each sample point, 1.5 texels long, that find geometry it sits behind
  // (pushed out to that surface's front) or that cuts through its footprint (nearGeometry).
  int leakRays = 8;               // count
  float offsetFraction = 0.05f;   // sample lift off its surface, × the texel's world size
  float minOffset = 1e-4f;        // metres: the least lift
};

// Stage clusters (clusters.h): the radiosity system's nodes.
struct ClusterOptions {
  float clusterSize = 0.5f;        // metres: largest extent of a cluster
  float clusterTexels = 4.0f;      // texel edges: largest extent in texels (<= 0: off)
  float maxNormalAngleDeg = 35.0f; // degrees: texels in a cluster stay within this normal cone
  int minTexels = 1;               // count: clusters are not split below this
  float adaptiveScale = 0.25f;     // clusters stay within this × their texels' median harmonic
                                   //   ray distance (<= 0: off)
  float maxDistanceRatio = 4.0f;   // texels whose ray distances differ by more are split apart
                                   //   (<= 1: off)
  float farScale = 4.0f;           // each far cluster level is this many times wider (<= 1: none)
  int farLevels = 1;               // count of far cluster levels (LinkOptions::farDistance)
};

// Stages gather, refine and links (gather.h, links.h): the gather points' rays and links.
struct LinkOptions {
  int texelRays = 128;         // cosine rays per gather point (a 2×2 block's texels share them)
  int nearRays = 128;          // more rays for texels near other geometry
  float nearDistance = 2.0f;   // texel edges: harmonic ray distance under which a texel is near
  float nearField = std::numeric_limits<float>::infinity();  // texel edges: the near rays'
                                                              //   reach (∞: every hit counts)
  float blockDistance = 8.0f;  // texel edges: texels nearer geometry gather alone, not in 2×2s
  float farDistance = 2.0f;    // far cluster radii: a hit farther links the far cluster (<= 0:
                               //   off)
  float farLightRatio = 1.5f;  // ... when its clusters receive each light within this ratio
                               //   (far_targets.h; <= 1: not checked)
  int sharedFarSpan = 4;       // texels: square of gather points pooling their far rays (<= 1:
                               //   off)
  float sharedFarPoints = 3.0f;      // gather points' rays a pool near geometry keeps
  float sharedFarLightRatio = 3.0f;  // pooled only when their far light is within this ratio
                                     //   (<= 1: not checked)
  int clusterRays = 256;       // rays per back-side cluster of double-sided geometry
  float minWeight = 0.0f;      // links below this form factor are dropped, the row rescaled
  float maxBackfaceFraction = 0.1f;  // a texel whose rays hit single-sided backs more is buried
  float maxEnclosedFraction = 0.75f; // ... or whose rays hit nearer than its size this often
  int filterPasses = 2;        // smoothing passes over the gather points (0: off)
  float filterReach = 0.5f;    // × the harmonic ray distance: how far a point smooths
  float filterMaxAngleDeg = 10.0f;   // degrees: neighbours' normals within this smooth together
  float filterLightRatio = 2.0f;     // first bounces of a light within this ratio smooth together
                                     //   (filter_light_edges.h; <= 1: not checked)
  float filterNoiseSigmas = 2.0f;    // ... or differing within this many standard deviations of
                                     //   their own noise (<= 0: not checked)
  bool lightMatch = true;      // near hits take the light of a texel the same lights reach
  float albedoDetail = 1.0f;   // texel edges: nearer hits read the texture at the hit (<= 0: off)
  float refineError = 0.1f;    // relative standard error above which a point casts more rays
                               //   (<= 0: no refined gather)
  int refineRays = 64;         // the most rays the refined gather adds to a point
  int glassSkySamples = 256;   // the most points on glass a texel samples the sky through it at
                               //   (glass_sky.h; 0: its cosine rays alone see that sky)
};

// Stage direct (direct.h): unit direct light per light and emissive material.
struct DirectOptions {
  int lightSamples = 16;      // first shadow rays per texel toward a light with a size
  int emissiveSamples = 16;   // first shadow rays per texel toward an emissive surface
  int penumbraSamples = 128;  // shadow rays where the first ones disagree (the penumbra)
};

// Stage probes (probe_transfer.h): the light probes' transfer.
struct ProbeOptions {
  int raysSide = 16;          // rays per probe: raysSide² over the sphere (octahedral grid)
  int binsSide = 8;           // bounced light gathered in binsSide² regions of the sphere
  int emitterSamples = 256;   // points chosen by area on each emissive material
  int lightSamples = 4;       // shadow rays per probe toward a light with a size
  float farDistance = 0.0f;   // far cluster radii for the probes' links (0: the links' own)
};

// Stage reflection capture (reflection_capture.h).
struct ReflectionOptions {
  uint32_t bounces = 1;  // capture passes after the diffuse one (Unity's Reflection Bounces)
};

// The reference path tracer (reference.h).
struct ReferenceOptions {
  int samples = 1024;     // paths per texel (or per pixel for views)
  int maxDepth = 64;      // bounces after which a path stops; Russian roulette from the third
  int specularDepth = 1;  // specular reflections referenceRadiance follows
};

// A whole bake (bake.h).
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
  int dilation = 2;                  // texels each chart is dilated into its padding
  bool directional = true;           // directional lightmaps: the bounced light's gradient
                                     //   atlases (runtime/directional.h)
  runtime::ProbeTetrahedra probes;   // light probes to bake (probes::tetrahedralize); none: empty
  ProbeOptions probeOptions;
  ReflectionOptions reflections;     // the scene's reflection probes' capture
  bool reference = false;            // every texel by the reference path tracer instead (no
                                     //   clusters, links or transport)
  ReferenceOptions referenceOptions;
};

// Quality presets (`afterglow bake --quality`): gather rays per gather point, first shadow rays
// per light, penumbra shadow rays, smoothing passes.
//   draft    64 / 8 / 64 / 3: a quick look
//   default  128 / 16 / 128 / 2
//   high     512 / 32 / 512 / 1
enum class Quality { Draft, Default, High };
BakeOptions bakePreset(Quality quality);

}  // namespace afterglow::baker
