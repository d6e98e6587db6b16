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
#include <limits>
#include <vector>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/gather.h"
#include "afterglow/baker/texels.h"
#include "afterglow/core/progress.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/transport.h"
#include "afterglow/scenes/scene.h"

namespace afterglow::baker {

class RayTracer;

struct LinkOptions {
  // Cosine-distributed gather rays per gather point: a texel near other geometry casts them
  // all, each texel of a 2×2 block on one surface a quarter.
  int texelRays = 128;
  // Texels close to other geometry (harmonic ray distance under nearDistance texel edges: the
  // corners of a room, the floor along a box) see light that changes fast over short
  // distances, which a gather point's rays resolve poorly; they cast nearRays more, which
  // count for what they hit within nearField texel edges (a finite reach leaves the far hits
  // to the first rays and keeps the links few). By default they count for everything: such a
  // texel in a dark corner that sees a sunlit floor far off through a gap is the gather's
  // noisiest, and on Sponza-sun counting them takes the bounced light's error from 17.7% to
  // 16.7% at 4 texels/m and 18.9% to 17.5% at 8, for 13% and 8% more links (at 8 or 32
  // edges nothing changes: the gain is in hits beyond 8 m). Since the gather's rays come from
  // tiled Sobol' sets (sampling::TiledSobol), 128 do what 192 did (15.6% / 14.4% at 4 / 8
  // texels/m against 16.3% / 14.3%, within a bake's own spread) for 4% fewer links.
  int nearRays = 128;
  float nearDistance = 2.0f;   // texel edges
  float nearField = std::numeric_limits<float>::infinity();  // texel edges
  // Texels whose harmonic ray distance is under this many texel edges gather alone, with a
  // full set of rays, instead of sharing a 2×2 block's: bounced light changes over a few
  // texels there.
  float blockDistance = 8.0f;
  // Hierarchical links: a gather point's hit farther than this × the radius of the far
  // cluster it lands in (ClusterOptions::farScale) links to that far cluster, so the many
  // rays that reach distant surfaces share links (fewer links: a smaller transport and a
  // faster bounce). The far cluster's light is its clusters' mean, which differs from the hit
  // cluster's own by less the farther it is seen from. <= 0: every hit links its cluster.
  float farDistance = 2.0f;    // far cluster radii
  // ... when the far cluster's clusters receive each light's direct light (and the sky's)
  // alike, the largest within this ratio of the smallest (far_targets.h, ClusterLight); else a
  // finer far cluster, or the hit's own cluster (still sharable as far). Also which gather
  // points may share a far field (alike far light). Needs the lights' direct light in the
  // transport. On Sponza-sun at 4 texels/m: bounced light 25.5% -> 22.2% RMSE against the
  // reference, 8% more links (issue 16). <= 1: not checked.
  float farLightRatio = 1.5f;
  // Shared far fields (runtime::TransportData::sharedFar): gather points whose texels lie in
  // one square of sharedFarSpan texels a side, on one surface and in sight of each other, and
  // of one kind (texels near other geometry, which gather alone, or 2×2 blocks), pool their
  // rays that link far clusters into one row; each point links that row with its own far
  // share. A pool of texels near other geometry is thinned to about sharedFarPoints points'
  // rays (sharedFarPoints × texelRays, whole points' stratified sets); a pool of blocks keeps
  // four points' rays (a square's four full blocks, one stratified set: thinned to three, it
  // left blotches a square wide).
  // Fewer links; fewer rays behind each point's far field, but its neighbours' rays, which the
  // smoothing would have mixed in anyway. Blocks share too since issue 16: on Sponza-sun at 4
  // texels/m that took 22% of the links away (9.3 M -> 7.3 M) at the same total error, and
  // the pool's 3 points' rays (was 2) spend them on less noise. sharedFarSpan <= 1: off.
  int sharedFarSpan = 4;         // texels
  float sharedFarPoints = 3.0f;  // gather points' rays
  // ... and whose far hits receive each light's direct light (and the sky's) alike: their
  // means within this ratio (with ClusterLight's floor). A point in a gap beside neighbours that
  // see a sunlit court must not take their far field (on Sponza-sun at 8 texels/m two such
  // points were 9x the reference). Looser than farLightRatio: a point's far light is itself a
  // Monte Carlo estimate, and 1.5 left noisy points alone (23.5% -> 24.4%). <= 1: not checked.
  float sharedFarLightRatio = 3.0f;
  int clusterRays = 256;       // rays per back-side cluster of double-sided geometry (fewer
                               //   for small ones: at most texelRays per texel)
  // Links below this form factor are left out and the rest of their row scaled up to keep its
  // sum. 0 keeps every link: leaving links out trades accuracy (the dropped light is assumed
  // to be the row's average) for a sparser matrix.
  float minWeight = 0.0f;
  // A texel whose rays hit the back of single-sided geometry more often than this is inside a
  // wall: it is marked invalid and later filled from its neighbours.
  float maxBackfaceFraction = 0.1f;  // unitless
  // A texel whose rays hit geometry nearer than its own size this often sits in a gap the
  // lightmap cannot resolve (light changes within its footprint): it is marked invalid too.
  float maxEnclosedFraction = 0.75f;  // unitless
  // Smoothing of bounced light (runtime::TransportData::pointFilter): passes of a tent over
  // neighbouring gather points on the same surface that lie within filterReach × the harmonic
  // ray distance of both (so corners and contact shadows stay sharp). 0 passes: off. The
  // texels then read the gather points around them with one more tent.
  int filterPasses = 2;
  float filterReach = 0.5f;  // unitless
  // ... and whose shading normals lie within this angle (at most the 30° of one surface).
  // 10°: across a curved or corrugated surface (Sponza's roof tiles, whose neighbours alternate
  // between facing the sun's bounce and facing away) wider smoothing carries one texel's light
  // onto its neighbours; on Sponza-sun 10° takes the bounced light's error from 28.7% to 25.6%
  // and changes nothing on flat walls (issue 16).
  float filterMaxAngleDeg = 10.0f;  // degrees
  // ... and, for a texel that gathers alone, whose gather points' first bounce of each light
  // (per unit light: geometry) lies within this ratio of each other (filter_light_edges.h).
  // On Sponza-sun at 8 texels/m: bounced light 27.7% -> 24.4%. <= 1: not checked.
  float filterLightRatio = 2.0f;
  // ... unless their difference is within this many standard deviations of the noise their
  // own rays leave in it (filter_light_edges.h). The ratio test assumed such texels' many rays
  // make their first bounce precise, but a dark one whose few rays find a small sunlit patch
  // is as noisy as it gets, and the test kept it from its neighbours. On Sponza-sun: bounced
  // light 15.1% -> 14.9% at 4 texels/m and 15.9% -> 15.4% at 8. <= 0: not checked.
  float filterNoiseSigmas = 2.0f;
  // A gather ray's hit nearer than four texel edges takes the light of a texel that the same
  // punctual lights reach as the hit point (gather_rays.h, TexelOfHit::lightMatch), or none
  // when its own texel is lit where the hit point is in shadow.
  bool lightMatch = true;
  // A hit nearer than this many texel edges on the front of a textured surface links its
  // cluster scaled by the texture's albedo at the hit point over the cluster's mean
  // (TexelGather::hitAlbedo): a wall a few cm from roof tiles sees those tiles, not the
  // cluster's average of them. On Sponza-sun at 4 texels/m the total error fell 5.2% -> 4.6%
  // (bounced light 15.8% -> 15.1%); 2 or 4 edges measure the same and cost more texture
  // reads. <= 0: off.
  float albedoDetail = 1.0f;  // texel edges
  // Refined gather (refineGather): a gather point whose estimate of some light's bounced light
  // plus direct light has a relative standard error above refineError (measured from its own
  // rays, per unit light) casts more rays, enough to bring it to refineError, at most
  // refineRays. On Sponza-sun at 4 texels/m: bounced light 16.1% -> 15.1% and total 4.8% ->
  // 4.6% against the reference, for 6% more rays and 5% more links. <= 0: off.
  float refineError = 0.1f;  // unitless
  int refineRays = 64;
};

// Traces every valid texel's gather rays, marks texels inside walls invalid (in `texels`), and
// remaps hits on them to a valid neighbour of the same chart. Seeded from (texel, ray).
Result<TexelGather> gatherTexels(const scenes::Scene& scene, const RayTracer& tracer,
                                 TexelSet& texels, const LinkOptions& options,
                                 Progress& progress = nullProgress());

// After the direct light (transport's light sources): more rays for the gather points whose
// bounced light the first rays leave uncertain (LinkOptions::refineError), appended to their
// texels' full sets in `gather`. Per unit light, so the rays do not depend on the lights'
// colours and intensities. Seeded from (texel, ray).
Status refineGather(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                    const Clusters& clusters, const runtime::TransportData& transport,
                    const LinkOptions& options, TexelGather& gather,
                    Progress& progress = nullProgress());

// The links of the gather points and of the back-side clusters (which cast rays of their own),
// how clusters and texels read the gather points, the smoothing between gather points, sky
// transfer, the materials and per-cluster texture modulation.
// With far cluster levels (coarser clusterings of the same texels, finest first; their back
// sides are not used), a gather point's hit links the coarsest far cluster it lies farther
// from than LinkOptions::farDistance × that cluster's radius
// (runtime::TransportData::farClusters), else the hit texel's cluster.
Status computeLinks(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                    const TexelGather& gather, const Clusters& clusters,
                    const LinkOptions& options, runtime::TransportData& transport,
                    Progress& progress = nullProgress(),
                    const std::vector<Clusters>& farLevels = {});

struct DirectOptions {
  // Shadow rays per texel and source: a first pass of lightSamples (lights with a size) or
  // emissiveSamples (emissive surfaces), then penumbraSamples wherever the first pass's rays
  // disagreed or disagreed with a neighbouring texel's (the penumbra and a texel around it),
  // so soft shadows come out smooth without paying for them where the light is all or nothing.
  int lightSamples = 16;
  int emissiveSamples = 16;
  int penumbraSamples = 128;
};

// One runtime::Source per light (unit colour and intensity) and per emissive material (unit
// radiance, sampled explicitly as area lights), with texel and cluster transfer.
Status computeDirect(const scenes::Scene& scene, const RayTracer& tracer, const TexelSet& texels,
                     const Clusters& clusters, const DirectOptions& options,
                     runtime::TransportData& transport, Progress& progress = nullProgress());

struct ProbeOptions {
  // Rays per probe: raysSide² over the whole sphere, at the centres of the cells of an
  // equal-area octahedral grid (Clarberg's map), the same directions for every probe
  // (probe_directions.h). Bounced light is gathered per region, binsSide² blocks of cells (at
  // least 2 × 2 cells; square when binsSide divides raysSide, which fits best): more regions
  // follow bounced light's direction more closely but make more links and a slower refresh.
  // The README's table: McGuire's box against the reference (SH L2) 16/8 2.6%, 18/6 2.9%,
  // 16/4 4.9%; Sponza's precompute 18% and 21% of the bake, its refresh per 10,000 probes
  // 2.9-3.1 and 2.8-3.1 ms (64 regions against 36).
  int raysSide = 16;
  int binsSide = 8;
  // Emissive surfaces seen by a probe: this many points chosen by area on each emissive
  // material, combined with the probe's rays that hit them (power heuristic, see
  // probe_transfer.cpp), so small lamps and emissive walls are both well sampled.
  int emitterSamples = 256;
  // Shadow rays toward a light with a size (the sun's disk, a sphere light): a probe's soft
  // shadow needs fewer than a texel's.
  int lightSamples = 4;
  // A probe's ray links the far cluster of the surface it hits from beyond this many of that
  // far cluster's radii (LinkOptions::farDistance for the probes; 0: the links' own). Lower
  // makes fewer links and a faster refresh, at a cost: McGuire's box against the reference goes
  // from 2.8% to 4.0% at 1 radius.
  float farDistance = 0.0f;
};

// The light probes' transfer (runtime::ProbeTransport; each source's probeTransfer) for the
// probes of `mesh`, after computeLinks and computeDirect have filled the transport: per probe,
// rays over the sphere give the sky's transfer, the emissive surfaces seen and, region by
// region, the links to the clusters (or the far clusters of `farLevels`, as computeLinks picks
// them with `farDistance` and `farLightRatio`) whose reflected light arrives; shadow rays give
// each light's. Seeded from (probe, ray): deterministic for any thread count.
Status computeProbeTransfer(const scenes::Scene& scene, const RayTracer& tracer,
                            const TexelSet& texels, const Clusters& clusters,
                            const std::vector<Clusters>& farLevels, float farDistance,
                            float farLightRatio,
                            const runtime::ProbeTetrahedra& mesh, const ProbeOptions& options,
                            runtime::TransportData& transport, Progress& progress = nullProgress());

}  // namespace afterglow::baker
