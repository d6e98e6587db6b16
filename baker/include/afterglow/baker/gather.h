// Stages gather and refine: every valid texel's gather rays, traced once, before clustering.
// What they hit decides both the texels' links and the clusters' (a front-side cluster gathers
// exactly what its texels gather, with all their rays), and how far they travel tells the
// clustering where light changes quickly (near corners, in gaps). TexelGather holds what they
// found: the input of the clustering and of the links.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

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

struct TexelGather {
  // Hit codes: the texel whose surface a ray reached, with kBackSide set when it reached the
  // back of a double-sided surface and kFar when a near-geometry ray (see below) went further
  // than its texel's near field; kNoHit for misses (sky) and absorbed rays (backs of
  // single-sided geometry, dynamic instances, surfaces without texels).
  static constexpr uint32_t kBackSide = 0x80000000u;
  static constexpr uint32_t kFar = 0x40000000u;
  static constexpr uint32_t kTexelMask = 0x3fffffffu;
  static constexpr uint32_t kNoHit = 0xffffffffu;
  uint32_t raysPerTexel = 0;  // LinkOptions::texelRays: the rays of a gather point
  // Texel t's rays are hits[hitStart[t] .. hitStart[t+1]), none for invalid texels. The first
  // fullRays[t] of them are stratified sets over the whole hemisphere and count for every hit;
  // the rest, cast only by texels near other geometry, count only for hits in the near field
  // (the far field, which changes slowly, is already sampled well enough by the first ones),
  // and carry kFar when they went beyond it, to be left out.
  std::vector<uint32_t> hitStart;
  std::vector<uint32_t> hits;
  // Per hit (as `hits`; empty when LinkOptions::albedoDetail is off): for hits on the front of
  // a textured material nearer than albedoDetail texel edges, the texture's grey modulation of
  // the albedo at the hit point (albedoCode: log-coded in steps of 3%, 1/512 to 2.5); 0 for
  // the others.
  std::vector<uint8_t> hitAlbedo;
  static uint8_t albedoCode(float grey) {
    if (!(grey > 0.0f)) return 1;
    return uint8_t(std::clamp(std::lround(223.0 + 24.0 * std::log2(double(grey))), 1l, 255l));
  }
  static float albedoOfCode(uint8_t code) { return std::exp2((float(code) - 223.0f) / 24.0f); }
  std::vector<uint16_t> fullRays;
  // Sky SH transfer, texel-major, kShCount per texel: over the texel's gather point's rays (a
  // texel of a 2×2 block casts a quarter of them).
  std::vector<float> sky;
  // Metres: N / Σ 1/d over the texel's gather point's rays (∞: open sky).
  std::vector<float> harmonicDistance;
  // Texels whose back side some ray reached (double-sided surfaces seen from behind): only
  // those get back-side clusters, since light on a back nobody sees goes nowhere. Their
  // harmonic distance seen from behind (an eighth of the rays) drives that clustering.
  std::vector<uint8_t> backSeen;
  std::vector<float> backHarmonicDistance;
  // Per texel, the lights its sample sees (LightVisibility): how the gather's hits were
  // light-matched (TexelOfHit::needsLightMatch in precompute/texel_of_hit.h), kept for
  // refineGather's rays. Empty without the check.
  std::vector<uint32_t> lightsReached;

  // Gather points (runtime::TransportData): blocks of up to 2×2 texels on one surface whose
  // rays are pooled into one row of links, each casting a share of raysPerTexel; texels near
  // other geometry are points of their own with all the rays.
  std::vector<uint32_t> pointOfTexel;  // per texel (kNoHit for invalid texels)
  std::vector<uint32_t> pointStart;    // texels of point p: pointTexels[pointStart[p] ..
  std::vector<uint32_t> pointTexels;   //   pointStart[p+1])
  uint32_t points() const { return pointStart.empty() ? 0 : uint32_t(pointStart.size() - 1); }
  // Per gather point, the rays its texels cast (every one, the refined gather's included).
  std::vector<uint32_t> pointRays() const {
    std::vector<uint32_t> rays(points(), 0);
    for (uint32_t p = 0; p < points(); ++p)
      for (uint32_t k = pointStart[p]; k < pointStart[p + 1]; ++k)
        rays[p] += hitStart[pointTexels[k] + 1] - hitStart[pointTexels[k]];
    return rays;
  }
};

// The cluster a gather hit code lands in: its texel's front cluster, or its back-side cluster;
// kNoTexel for a miss.
inline uint32_t clusterOfHit(const Clusters& clusters, uint32_t code) {
  if (code == TexelGather::kNoHit) return runtime::kNoTexel;
  const uint32_t t = code & TexelGather::kTexelMask;
  return (code & TexelGather::kBackSide) ? clusters.texelBackCluster[t] : clusters.texelCluster[t];
}

// Traces every valid texel's gather rays, marks texels inside walls invalid (in `texels`), and
// remaps hits on them to a valid neighbour of the same chart. Seeded from (texel, ray).
Result<TexelGather> gatherTexels(const scenes::Scene& scene, const trace::RayTracer& tracer,
                                 TexelSet& texels, const LinkOptions& options,
                                 Progress& progress = nullProgress());

// After the direct light (transport's light sources): more rays for the gather points whose
// bounced light the first rays leave uncertain (LinkOptions::refineError), appended to their
// texels' full sets in `gather`. Per unit light, so the rays do not depend on the lights'
// colours and intensities. Seeded from (texel, ray).
Status refineGather(const scenes::Scene& scene, const trace::RayTracer& tracer,
                    const TexelSet& texels, const Clusters& clusters,
                    const runtime::TransportData& transport, const LinkOptions& options,
                    TexelGather& gather, Progress& progress = nullProgress());

}  // namespace afterglow::baker
