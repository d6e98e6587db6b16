// Stages 3 and 4 of the precompute: the texels' gather rays, form factors (texel -> cluster,
// cluster -> cluster, sky transfer) and unit direct light per source, written into
// runtime::TransportData.
//
// The gather rays are traced once per texel, before clustering: what they hit decides both the
// texels' links and the clusters' (a front-side cluster gathers exactly what its texels
// gather, with all their rays), and how far they travel tells the clustering where light
// changes quickly (near corners, in gaps). Only the back sides of double-sided surfaces, which
// have no texels of their own, cast rays of their own.
#pragma once

#include <cstdint>
#include <vector>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

class RayTracer;

struct LinkOptions {
  int texelRays = 64;          // cosine-distributed gather rays per texel
  int clusterRays = 256;       // rays per back-side cluster of double-sided geometry
  float minWeight = 1e-4f;     // links below this form factor are folded into the nearest kept one
  // A texel whose rays hit the back of single-sided geometry more often than this is inside a
  // wall: it is marked invalid and later filled from its neighbours.
  float maxBackfaceFraction = 0.1f;  // unitless
  // Smoothing of the texels' bounced light (runtime::TransportData::texelNeighbours): passes of
  // a 3×3 tent over neighbours on the same surface that lie within filterReach × the harmonic
  // ray distance of both (so corners and contact shadows stay sharp). 0 passes: off.
  int filterPasses = 2;
  float filterReach = 0.5f;  // unitless
};

// What every texel's gather rays found.
struct TexelGather {
  // Hit codes: the texel whose surface a ray reached, with kBackSide set when it reached the
  // back of a double-sided surface; kNoHit for misses (sky) and absorbed rays (backs of
  // single-sided geometry, dynamic instances, surfaces without texels).
  static constexpr uint32_t kBackSide = 0x80000000u;
  static constexpr uint32_t kNoHit = 0xffffffffu;
  uint32_t raysPerTexel = 0;
  std::vector<uint32_t> hits;              // texel-major, raysPerTexel per texel
  std::vector<float> sky;                  // texel-major, kShCount per texel: sky SH transfer
  std::vector<float> harmonicDistance;     // metres: N / Σ 1/d over the rays (∞: open sky)
  // The same seen from the back of double-sided surfaces (a quarter of the rays; empty
  // entries, ∞, for single-sided ones), so their back sides cluster by their own surroundings.
  std::vector<float> backHarmonicDistance;
};

// Traces every valid texel's gather rays, marks texels inside walls invalid (in `texels`), and
// remaps hits on them to a valid neighbour of the same chart. Seeded from (texel, ray).
Result<TexelGather> gatherTexels(const scenes::Scene& scene, const RayTracer& tracer,
                                 TexelSet& texels, const LinkOptions& options,
                                 Progress& progress = nullProgress());

// Texel and cluster links and sky transfer from the gather (plus the back-side clusters' own
// rays), the materials and per-cluster texture modulation.
Status computeLinks(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                    const TexelGather& gather, const Clusters& clusters,
                    const LinkOptions& options, runtime::TransportData& transport,
                    Progress& progress = nullProgress());

struct DirectOptions {
  int lightSamples = 16;     // shadow rays per texel per light with a size (soft shadows)
  int emissiveSamples = 64;  // samples per texel over all emissive triangles
  int penumbraSamples = 256; // shadow rays per texel and light where the first ones disagree
                             //   (the penumbra), so soft shadows come out smooth
};

// One runtime::Source per light (unit colour and intensity) and per emissive material (unit
// radiance, sampled explicitly as area lights), with texel and cluster transfer.
Status computeDirect(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                     const Clusters& clusters, const DirectOptions& options,
                     runtime::TransportData& transport, Progress& progress = nullProgress());

}  // namespace afterglow::baker
